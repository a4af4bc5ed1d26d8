#include "io/detail/open_image.h"

#include <OpenImageIO/filesystem.h>
#include <fmt/format.h>

#include <cstdint>
#include <fstream>

namespace modestack::io::detail {
namespace {

// OpenEXR allocates an attribute's declared size before reading it: a damaged
// 280-byte header that declared a 1.7 GB string made `info` take 1.8 GB and 6 s
// (found by fuzz/exr_header). Walk the first header and refuse any attribute
// larger than the file. Not an EXR, or a header we cannot walk: leave it to OIIO.
// Returns the problem, or an empty string.
std::string exr_header_problem(const std::string& file)
{
    std::ifstream in(file, std::ios::binary);
    // OIIO calls an empty file "not an OpenEXR file"; say what it is (an
    // interrupted copy, a render that died before writing).
    if (in && in.peek() == std::ifstream::traits_type::eof())
        return "empty file (0 bytes)";
    std::uint32_t magic = 0, version = 0;
    if (!in.read(reinterpret_cast<char*>(&magic), 4) || !in.read(reinterpret_cast<char*>(&version), 4) ||
        magic != 20000630)
        return {};
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
            return {};
        std::int64_t left = file_size - static_cast<std::int64_t>(in.tellg());
        if (size < 0 || size > left)
            return fmt::format("damaged header: attribute '{}' claims {} bytes, only {} are left in the file", name,
                               size, left);
        in.seekg(size, std::ios::cur);
    }
    return {};
}

}  // namespace

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& file, std::string& reason)
{
    std::string extension = OIIO::Filesystem::extension(file, false);
    if (extension.empty()) {
        reason = "no file extension to choose an image reader";
        return nullptr;
    }
    auto input = OIIO::ImageInput::create(extension);  // by extension only: nothing is opened
    if (!input) {
        reason = OIIO::geterror();
        return nullptr;
    }
    OIIO::ImageSpec spec;
    if (!input->open(file, spec)) {
        reason = input->geterror();
        return nullptr;
    }
    return input;
}

std::unique_ptr<OIIO::ImageInput> open_checked_image(const std::string& file, int frame_number)
{
    auto refuse = [&](const std::string& problem) { return Error(ErrorKind::BadInput, problem, file, frame_number); };
    if (!OIIO::Filesystem::exists(file))
        throw refuse("file not found");
    if (OIIO::Filesystem::is_directory(file))
        throw refuse("is a directory, not an image file");
    if (std::string problem = exr_header_problem(file); !problem.empty())
        throw refuse(problem);
    std::string reason;
    auto input = open_image(file, reason);
    if (!input)
        throw refuse(fmt::format("cannot read image header ({})", reason.empty() ? "unknown format" : reason));
    return input;
}

}  // namespace modestack::io::detail
