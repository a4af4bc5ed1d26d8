#include "io/output_format.h"

#include <array>
#include <cstdlib>
#include <string_view>

namespace modestack::io {
namespace {

constexpr std::array<std::string_view, 10> kCompressions{"none",  "rle", "zips", "zip",  "piz",
                                                         "pxr24", "b44", "b44a", "dwaa", "dwab"};
constexpr std::array<std::string_view, 5> kLossless{"none", "rle", "zips", "zip", "piz"};

template <std::size_t Size>
bool is_one_of(const std::array<std::string_view, Size>& names, const std::string& name)
{
    for (std::string_view known : names)
        if (name == known)
            return true;
    return false;
}

} // namespace

const char* compression_names()
{
    return "none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa, dwab";
}

CompressionName split_compression(const std::string& name)
{
    const std::size_t colon = name.find(':');
    if (colon == std::string::npos)
        return {name, -1.0f};
    const std::string level = name.substr(colon + 1);
    char* end = nullptr;
    const float value = std::strtof(level.c_str(), &end);
    // A level that is not a number above 0 makes the name unknown (method "").
    if (level.empty() || end != level.c_str() + level.size() || !(value > 0.0f) || value > 1e6f)
        return {"", -1.0f};
    return {name.substr(0, colon), value};
}

bool is_compression_name(const std::string& name)
{
    const CompressionName split = split_compression(name);
    if (split.dwa_level > 0.0f)
        return split.method == "dwaa" || split.method == "dwab";
    return name.find(':') == std::string::npos && is_one_of(kCompressions, name);
}

bool is_lossless_compression(const std::string& compression)
{
    return is_one_of(kLossless, compression.substr(0, compression.find(':'))); // "zip:4" is zip
}

std::string output_compression(const std::string& requested, const std::string& input_compression)
{
    if (!requested.empty())
        return requested;
    return is_lossless_compression(input_compression) ? input_compression : "zip";
}

} // namespace modestack::io
