// Walks OpenEXR headers: magic and version, then per part a list of attributes
// (name, type, size, value) ended by an empty name; a multi-part file ends the
// list of parts with one more empty name. The offset tables follow.
#include "io/detail/exr_headers.h"

#include <fmt/format.h>

#include <fstream>

namespace modestack::io::detail {
namespace {

constexpr std::uint32_t kExrMagic = 20000630;
constexpr std::uint32_t kMultipartBit = 0x1000;
constexpr std::size_t kLongestName = 255; // OpenEXR's long-names limit

} // namespace

ExrHeaders walk_exr_headers(const std::string& file)
{
    ExrHeaders headers;
    std::ifstream in(file, std::ios::binary);
    std::uint32_t magic = 0, version = 0;
    if (!in.read(reinterpret_cast<char*>(&magic), 4) || !in.read(reinterpret_cast<char*>(&version), 4) ||
        magic != kExrMagic)
        return headers;
    headers.is_exr = true;
    headers.multipart = (version & kMultipartBit) != 0;
    in.seekg(0, std::ios::end);
    headers.file_size = in.tellg();
    in.seekg(8);
    auto read_name = [&](std::string& name) {
        name.clear();
        char c = 0;
        while (in.get(c) && c != '\0' && name.size() <= kLongestName)
            name.push_back(c);
        return static_cast<bool>(in) && c == '\0';
    };
    std::string name, type;
    for (;;) {
        while (read_name(name) && !name.empty()) {
            std::int32_t size = 0;
            if (!read_name(type) || !in.read(reinterpret_cast<char*>(&size), 4))
                return headers;
            std::int64_t left = headers.file_size - static_cast<std::int64_t>(in.tellg());
            if (size < 0 || size > left) {
                headers.problem =
                    fmt::format("damaged header: attribute '{}' claims {} bytes, only {} are left in "
                                "the file",
                                name, size, left);
                return headers;
            }
            in.seekg(size, std::ios::cur);
        }
        if (!in)
            return headers; // cut inside the headers: the reader says so
        // The empty name that ends a single part's header, or the list of parts.
        if (!headers.multipart || in.peek() == '\0')
            break;
    }
    if (headers.multipart)
        in.get();
    headers.tables_offset = in ? static_cast<std::int64_t>(in.tellg()) : -1;
    return headers;
}

} // namespace modestack::io::detail
