// Parsing of option values that CLI11 does not know: memory and image sizes.
#pragma once

#include <cstdint>
#include <string>

namespace modestack::app {

/// Parses "512M", "2G", "1.5G", "800K" or plain bytes (binary units, K = 1024).
/// Throws a usage error naming `option` when malformed or not positive.
std::int64_t parse_memory_size(const std::string& text, const std::string& option);

/// Parses an image size "WIDTHxHEIGHT" (each 1 to 65536). Throws a usage error
/// naming --size when malformed.
void parse_image_size(const std::string& text, int& width, int& height);

}  // namespace modestack::app
