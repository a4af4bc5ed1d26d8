// Pixel masks for partial renders (`modestack render --mask`, used by refine):
// a mask frame is any image whose first channel is non-zero where a pixel is to
// be rendered.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::io {

/// Reads the first channel of `file` as a mask (1 = non-zero). Throws Error
/// naming the file when it cannot be read or is not `width` × `height`.
std::vector<std::uint8_t> read_mask(const std::string& file, int width, int height);

}  // namespace modestack::io
