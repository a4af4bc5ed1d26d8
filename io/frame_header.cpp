#include "io/frame_header.h"

#include "io/detail/open_image.h"
#include "io/layers.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

namespace modestack::io {

namespace {

ImagePart describe_part(const OIIO::ImageSpec& spec)
{
    ImagePart part;
    part.name = spec.get_string_attribute("oiio:subimagename");
    part.x = spec.x;
    part.y = spec.y;
    part.width = spec.width;
    part.height = spec.height;
    part.tile_width = spec.tile_width;
    part.tile_height = spec.tile_height;
    part.deep = spec.deep;
    part.channel_names = spec.channelnames;
    for (int c = 0; c < spec.nchannels; ++c)
        part.channel_types.push_back(spec.channelformat(c).c_str());
    part.compression = spec.get_string_attribute("compression", "none");
    return part;
}

} // namespace

FrameHeader read_frame_header(const std::string& file)
{
    auto input = detail::open_checked_image(file);
    const OIIO::ImageSpec& spec = input->spec();
    FrameHeader header;
    header.file = file;
    header.format_name = input->format_name();
    static_cast<ImagePart&>(header) = describe_part(spec);
    header.full_x = spec.full_x;
    header.full_y = spec.full_y;
    header.full_width = spec.full_width;
    header.full_height = spec.full_height;
    for (const auto& attribute : spec.extra_attribs) {
        std::string name = attribute.name().string();
        header.attributes.emplace_back(name, fmt::format("{} {}", attribute.type().c_str(),
                                                         spec.metadata_val(attribute, true)));
    }
    for (int part = 0; input->seek_subimage(part, 0); ++part)
        header.parts.push_back(describe_part(input->spec()));
    return header;
}

std::vector<std::string> channels_as_read(const FrameHeader& header)
{
    if (header.parts.size() <= 1)
        return header.channel_names;
    std::vector<std::string> names;
    for (const ImagePart& part : header.parts) {
        const std::vector<std::string> part_names = part_channel_names(part.name, part.channel_names);
        names.insert(names.end(), part_names.begin(), part_names.end());
    }
    return names;
}

std::optional<std::string> find_attribute(const FrameHeader& header, const std::string& name)
{
    for (const auto& [attribute, value] : header.attributes)
        if (attribute == name)
            return value;
    return std::nullopt;
}

std::string attribute_value(const std::string& typed_value)
{
    const size_t space = typed_value.find(' ');
    std::string value = space == std::string::npos ? typed_value : typed_value.substr(space + 1);
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"')
        value = value.substr(1, value.size() - 2);
    return value;
}

std::optional<double> attribute_number(const std::string& typed_value)
{
    const std::string value = attribute_value(typed_value);
    if (value.empty())
        return std::nullopt;
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    if (end != value.c_str() + value.size() || !std::isfinite(number))
        return std::nullopt;
    return number;
}

std::optional<std::int64_t> attribute_count(const std::string& typed_value, std::int64_t largest)
{
    const std::optional<double> number = attribute_number(typed_value);
    if (!number || *number < 1 || *number > static_cast<double>(largest) || *number != std::floor(*number))
        return std::nullopt;
    return static_cast<std::int64_t>(*number);
}

std::string describe_window(int x, int y, int width, int height)
{
    if (x == 0 && y == 0)
        return fmt::format("{}x{}", width, height);
    return fmt::format("{}x{}{:+d}{:+d}", width, height, x, y);
}

}  // namespace modestack::io
