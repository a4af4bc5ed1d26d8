// PNG images encoded to and decoded from memory, for outputs that embed images
// instead of writing them beside themselves (the --report HTML page carries its
// images as data: URIs). 8-bit only: the page decodes them on a canvas.
#pragma once

#include <cstdint>
#include <vector>

namespace modestack::io {

/// An 8-bit image, interleaved, y = 0 at the top.
struct Image8 {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<std::uint8_t> pixels;  ///< width × height × channels
};

/// The PNG file bytes of `image` (1 to 4 channels). Throws an internal error
/// when OpenImageIO cannot encode it or the image is empty or inconsistent.
std::vector<std::uint8_t> encode_png(const Image8& image);

/// Decodes PNG file bytes. Throws Error (bad input) when they are not a PNG.
Image8 decode_png(const std::vector<std::uint8_t>& bytes);

}  // namespace modestack::io
