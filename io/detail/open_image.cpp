#include "io/detail/open_image.h"

#include "io/detail/exr_headers.h"

#include <OpenImageIO/filesystem.h>
#include <fmt/format.h>

#include <fstream>

namespace modestack::io::detail {
namespace {

// OpenEXR allocates an attribute's declared size before reading it: a damaged
// 280-byte header that declared a 1.7 GB string made `info` take 1.8 GB and 6 s
// (found by fuzz/exr_header). Walk the headers (every part's) and refuse any
// attribute larger than the file. Not an EXR, or headers we cannot walk: leave
// it to OIIO. Returns the problem, or an empty string.
std::string exr_header_problem(const std::string& file)
{
    // OIIO calls an empty file "not an OpenEXR file"; say what it is (an
    // interrupted copy, a render that died before writing).
    std::ifstream in(file, std::ios::binary);
    if (in && in.peek() == std::ifstream::traits_type::eof())
        return "empty file (0 bytes)";
    return walk_exr_headers(file).problem;
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
