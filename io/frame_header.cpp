#include "io/frame_header.h"

#include "core/common/error.h"
#include "io/detail/open_image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cstdint>
#include <fstream>

namespace modestack::io {

// OpenEXR allocates an attribute's declared size before reading it: a damaged
// 280-byte header that declared a 1.7 GB string made `info` take 1.8 GB and 6 s
// (found by fuzz/exr_header). Walk the first header and refuse any attribute
// larger than the file. Not an EXR, or a header we cannot walk: leave it to OIIO.
void check_exr_attribute_sizes(const std::string& file)
{
    std::ifstream in(file, std::ios::binary);
    // OIIO calls an empty file "not an OpenEXR file"; say what it is (an
    // interrupted copy, a render that died before writing).
    if (in && in.peek() == std::ifstream::traits_type::eof())
        throw bad_input(file, "empty file (0 bytes)");
    std::uint32_t magic = 0, version = 0;
    if (!in.read(reinterpret_cast<char*>(&magic), 4) || !in.read(reinterpret_cast<char*>(&version), 4) ||
        magic != 20000630)
        return;
    in.seekg(0, std::ios::end);
    const std::int64_t file_size = in.tellg();
    in.seekg(8);
    auto read_name = [&](std::string& name) {
        name.clear();
        char c = 0;
        while (in.get(c) && c != '\0' && name.size() < 256)
            name.push_back(c);
        return static_cast<bool>(in) && c == '\0';
    };
    std::string name, type;
    while (read_name(name) && !name.empty()) {
        std::int32_t size = 0;
        if (!read_name(type) || !in.read(reinterpret_cast<char*>(&size), 4))
            return;
        std::int64_t left = file_size - static_cast<std::int64_t>(in.tellg());
        if (size < 0 || size > left)
            throw bad_input(file, fmt::format("damaged header: attribute '{}' claims {} bytes, only {} are left in "
                                              "the file",
                                              name, size, left));
        in.seekg(size, std::ios::cur);
    }
}

FrameHeader read_frame_header(const std::string& file)
{
    if (!OIIO::Filesystem::exists(file))
        throw bad_input(file, "file not found");
    if (OIIO::Filesystem::is_directory(file))
        throw bad_input(file, "is a directory, not an image file");
    check_exr_attribute_sizes(file);
    std::string reason;
    auto input = detail::open_image(file, reason);
    if (!input)
        throw bad_input(file, fmt::format("cannot read image header ({})", reason.empty() ? "unknown format" : reason));
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
