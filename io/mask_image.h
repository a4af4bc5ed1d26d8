// Pixel masks for partial renders (`modestack render --mask`, used by refine):
// a mask frame is any image whose first channel is non-zero where a pixel is to
// be rendered. Refine's masks also carry the blend weight of every pixel
// (channel "weight"), which `refine --blend` reads back.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::io {

/// Reads the first channel of `file` as a mask (1 = non-zero). Throws Error
/// naming the file when it cannot be read or is not `width` × `height`.
std::vector<std::uint8_t> read_mask(const std::string& file, int width, int height);

/// Reads the blend weights of a mask frame: its "weight" channel, else its
/// first channel (a matte painted in a compositor), clamped to [0, 1]. Throws
/// Error naming the file when it cannot be read, is not `width` × `height`, or
/// holds a weight that is not a number.
std::vector<float> read_mask_weights(const std::string& file, int width, int height);

}  // namespace modestack::io
