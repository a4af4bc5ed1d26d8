#include "io/mask_image.h"

#include "core/common/error.h"
#include "io/detail/open_image.h"
#include "io/frame_header.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

namespace modestack::io {

std::vector<std::uint8_t> read_mask(const std::string& file, int width, int height)
{
    FrameHeader header = read_frame_header(file);
    if (header.width != width || header.height != height)
        throw bad_input(file, fmt::format("mask is {}x{} but the render is {}x{}", header.width, header.height, width,
                                          height));
    std::string reason;
    auto input = detail::open_image(file, reason);
    if (!input)
        throw bad_input(file, fmt::format("cannot read mask ({})", reason));
    std::vector<float> values(static_cast<size_t>(width) * height);
    if (!input->read_image(0, 0, 0, 1, OIIO::TypeFloat, values.data()))
        throw bad_input(file, fmt::format("cannot read mask ({})", input->geterror()));
    std::vector<std::uint8_t> mask(values.size());
    for (size_t i = 0; i < values.size(); ++i)
        mask[i] = values[i] != 0.0f ? 1 : 0;
    return mask;
}

}  // namespace modestack::io
