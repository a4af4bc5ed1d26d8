#include "app/option_values.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>

namespace modestack::app {

std::int64_t parse_memory_size(const std::string& text, const std::string& option)
{
    char* end = nullptr;
    double value = std::strtod(text.c_str(), &end);
    std::string unit = end ? std::string(end) : std::string();
    double scale = 0;
    if (unit.empty() || unit == "B")
        scale = 1;
    else if (unit == "K" || unit == "KB" || unit == "KiB")
        scale = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MiB")
        scale = 1024.0 * 1024;
    else if (unit == "G" || unit == "GB" || unit == "GiB")
        scale = 1024.0 * 1024 * 1024;
    // At least one byte ("0.1" would round to 0) and finite ("1e400" or "inf" would
    // overflow the conversion to an integer).
    double bytes = value * scale;
    if (end == text.c_str() || scale == 0 || !(bytes >= 1) || !(bytes < 0x1p62))
        throw usage_error(fmt::format("{} '{}': not a memory size (examples: 512M, 2G)", option, text));
    return static_cast<std::int64_t>(bytes);
}

void parse_image_size(const std::string& text, int& width, int& height)
{
    unsigned long long w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%llux%llu%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 65536 || h > 65536)
        throw usage_error(fmt::format("--size '{}': write WIDTHxHEIGHT, e.g. 320x240 (each 1 to 65536)", text));
    width = static_cast<int>(w);
    height = static_cast<int>(h);
}

}  // namespace modestack::app
