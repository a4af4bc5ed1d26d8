#include "io/partial_render.h"

#include "core/common/error.h"
#include "io/detail/open_image.h"
#include "io/frame_header.h"
#include "io/layers.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>

namespace modestack::io {
namespace {

struct PartialLayout {
    std::vector<int> value_channels, variance_channels; // indices into the file's channels
};

// The layer's R, G and B channels, in that order (files store them in any order).
std::vector<int> colour_channels(const std::vector<SelectedLayer>& layers,
                                 const std::vector<std::string>& names, const std::string& what,
                                 const std::string& file)
{
    const SelectedLayer& layer = layers.front();
    std::vector<int> rgb;
    for (const char* wanted : {"R", "G", "B"})
        for (int index : layer.channel_indices) {
            std::string layer_name, component;
            split_channel_name(names[index], layer_name, component);
            if (component == wanted)
                rgb.push_back(index);
        }
    if (rgb.size() != 3)
        throw bad_input(file, fmt::format("{} {} must have R, G and B channels", what, layer.name));
    return rgb;
}

PartialLayout check_layout(const FrameHeader& header, const std::string& layer,
                           const std::string& variance_layer, int full_width, int full_height)
{
    const std::string& file = header.file;
    if (header.full_width != full_width || header.full_height != full_height)
        throw bad_input(file, fmt::format("the re-render is {}x{} but the denoised frames are {}x{}",
                                          header.full_width, header.full_height, full_width, full_height));
    const int x0 = header.x - header.full_x, y0 = header.y - header.full_y;
    if (x0 < 0 || y0 < 0 || x0 + header.width > full_width || y0 + header.height > full_height)
        throw bad_input(file, fmt::format("its data window {} is not inside its display window {}",
                                          describe_window(header.x, header.y, header.width, header.height),
                                          describe_window(header.full_x, header.full_y, header.full_width,
                                                          header.full_height)));
    PartialLayout layout;
    const std::vector<std::string>& names = header.channel_names;
    layout.value_channels = colour_channels(select_layers(names, {layer}, file), names, "layer", file);
    layout.variance_channels =
        colour_channels(select_layers(names, {variance_layer}, file), names, "variance layer", file);
    return layout;
}

// Where the file's pixels sit in its display window.
PartialRender placed(const FrameHeader& header)
{
    PartialRender render;
    render.file = header.file;
    render.x0 = header.x - header.full_x;
    render.y0 = header.y - header.full_y;
    render.width = header.width;
    render.height = header.height;
    return render;
}

} // namespace

PartialRender check_partial_render(const std::string& file, const std::string& layer,
                                   const std::string& variance_layer, int full_width, int full_height)
{
    const FrameHeader header = read_frame_header(file);
    check_layout(header, layer, variance_layer, full_width, full_height);
    return placed(header);
}

PartialRender read_partial_render(const std::string& file, const std::string& layer,
                                  const std::string& variance_layer, int full_width, int full_height)
{
    const FrameHeader header = read_frame_header(file);
    const PartialLayout layout = check_layout(header, layer, variance_layer, full_width, full_height);
    PartialRender render = placed(header);
    // One read of the channel span that holds both layers (adjacent in most files).
    std::vector<int> wanted = layout.value_channels;
    wanted.insert(wanted.end(), layout.variance_channels.begin(), layout.variance_channels.end());
    const int first = *std::min_element(wanted.begin(), wanted.end());
    const int span = *std::max_element(wanted.begin(), wanted.end()) + 1 - first;
    const std::size_t pixels = static_cast<std::size_t>(render.width) * render.height;
    std::vector<float> channels(pixels * span);
    auto input = detail::open_checked_image(file);
    if (!input->read_image(0, 0, first, first + span, OIIO::TypeFloat, channels.data()))
        throw bad_input(file, fmt::format("cannot read the re-rendered pixels ({})", input->geterror()));
    render.value.resize(pixels * 3);
    render.variance.resize(pixels * 3);
    for (std::size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            render.value[p * 3 + c] = channels[p * span + layout.value_channels[c] - first];
            render.variance[p * 3 + c] = channels[p * span + layout.variance_channels[c] - first];
        }
    return render;
}

} // namespace modestack::io
