#include "io/frame_header.h"

#include "io/detail/open_image.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

namespace modestack::io {

FrameHeader read_frame_header(const std::string& file)
{
    auto input = detail::open_checked_image(file);
    const OIIO::ImageSpec& spec = input->spec();
    FrameHeader header;
    header.file = file;
    header.format_name = input->format_name();
    header.x = spec.x;
    header.y = spec.y;
    header.width = spec.width;
    header.height = spec.height;
    header.full_x = spec.full_x;
    header.full_y = spec.full_y;
    header.full_width = spec.full_width;
    header.full_height = spec.full_height;
    header.tile_width = spec.tile_width;
    header.tile_height = spec.tile_height;
    header.deep = spec.deep;
    header.channel_names = spec.channelnames;
    for (int c = 0; c < spec.nchannels; ++c)
        header.channel_types.push_back(spec.channelformat(c).c_str());
    header.compression = spec.get_string_attribute("compression", "none");
    int subimages = 1;
    while (input->seek_subimage(subimages, 0))
        ++subimages;
    header.subimages = subimages;
    for (const auto& attribute : spec.extra_attribs) {
        std::string name = attribute.name().string();
        header.attributes.emplace_back(name, fmt::format("{} {}", attribute.type().c_str(),
                                                         spec.metadata_val(attribute, true)));
    }
    return header;
}

std::string describe_window(int x, int y, int width, int height)
{
    if (x == 0 && y == 0)
        return fmt::format("{}x{}", width, height);
    return fmt::format("{}x{}{:+d}{:+d}", width, height, x, y);
}

}  // namespace modestack::io
