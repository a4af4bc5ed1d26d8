// Re-rendered pixels from any renderer, for `refine --blend`: one frame's
// layer and its variance, either a full frame or a crop window. A crop is an
// EXR whose data window is the rendered part of the display window (what
// Arnold, RenderMan, Karma and Blender write for a region render with
// "crop to border"), so its offset needs no side file.
#pragma once

#include <string>
#include <vector>

namespace modestack::io {

/// One frame's re-rendered layer: `value` and `variance` hold the data
/// window's pixels (width·height·3 floats, R, G, B interleaved, rows from the
/// top); x0, y0 is the data window's offset inside the display window.
struct PartialRender {
    std::string file;
    int x0 = 0, y0 = 0, width = 0, height = 0;
    std::vector<float> value, variance;
    bool contains(int x, int y) const { return x >= x0 && x < x0 + width && y >= y0 && y < y0 + height; }
};

/// Checks the header of `file` without reading pixels: its display window is
/// `full_width` × `full_height` and holds the data window, and it has the
/// `layer` and `variance_layer` (io/layers.h selectors), each with R, G and
/// B channels. Returns where its pixels sit (value and variance left empty).
/// Throws a bad-input Error naming the file otherwise.
PartialRender check_partial_render(const std::string& file, const std::string& layer,
                                   const std::string& variance_layer, int full_width, int full_height);

/// check_partial_render, then reads the two layers' pixels as float.
PartialRender read_partial_render(const std::string& file, const std::string& layer,
                                  const std::string& variance_layer, int full_width, int full_height);

} // namespace modestack::io
