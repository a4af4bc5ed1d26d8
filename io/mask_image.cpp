#include "io/mask_image.h"

#include "core/common/error.h"
#include "io/detail/open_image.h"
#include "io/frame_header.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace modestack::io {

namespace {

// One channel of a mask frame as float, after checking its size.
std::vector<float> read_mask_channel(const std::string& file, int width, int height, bool weight_channel)
{
    FrameHeader header = read_frame_header(file);
    if (header.width != width || header.height != height)
        throw bad_input(file, fmt::format("mask is {}x{} but the render is {}x{}", header.width, header.height, width,
                                          height));
    int channel = 0;
    if (weight_channel)
        for (std::size_t c = 0; c < header.channel_names.size(); ++c)
            if (header.channel_names[c] == "weight")
                channel = static_cast<int>(c);
    std::string reason;
    auto input = detail::open_image(file, reason);
    if (!input)
        throw bad_input(file, fmt::format("cannot read mask ({})", reason));
    std::vector<float> values(static_cast<size_t>(width) * height);
    if (!input->read_image(0, 0, channel, channel + 1, OIIO::TypeFloat, values.data()))
        throw bad_input(file, fmt::format("cannot read mask ({})", input->geterror()));
    return values;
}

} // namespace

std::vector<float> read_mask_weights(const std::string& file, int width, int height)
{
    std::vector<float> weights = read_mask_channel(file, width, height, true);
    for (float& weight : weights) {
        if (std::isnan(weight))
            throw bad_input(file, "a mask weight is not a number");
        weight = std::clamp(weight, 0.0f, 1.0f);
    }
    return weights;
}

std::vector<std::uint8_t> read_mask(const std::string& file, int width, int height)
{
    std::vector<float> values = read_mask_channel(file, width, height, false);
    std::vector<std::uint8_t> mask(values.size());
    for (size_t i = 0; i < values.size(); ++i)
        mask[i] = values[i] != 0.0f ? 1 : 0;
    return mask;
}

}  // namespace modestack::io
