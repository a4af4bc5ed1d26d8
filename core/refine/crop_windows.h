// Crop windows for renderers that re-render part of a frame (`refine
// --masks-only`): the bounding boxes of the mask's clusters (8-connected
// components), merged while a merge costs fewer pixels than it saves, and the
// forms renderers take them in. Each window is rendered as a separate crop, so
// it costs its pixels plus a fixed overhead (process start, scene load,
// acceleration structure, filter margin), expressed in pixels of render time
// at the re-render's spp: a union box renders the gap between two clusters,
// two boxes pay the overhead twice.
#pragma once

#include <cstdint>
#include <vector>

namespace modestack::refine {

/// A rectangle of pixels: x0 ≤ x < x1, y0 ≤ y < y1 (min inclusive, max
/// exclusive), y = 0 at the top row, as in an EXR data window relative to the
/// display window (whose max is inclusive: x1 − 1, y1 − 1).
struct PixelWindow {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    std::int64_t area() const { return static_cast<std::int64_t>(x1 - x0) * (y1 - y0); }
    bool operator==(const PixelWindow& other) const
    {
        return x0 == other.x0 && y0 == other.y0 && x1 == other.x1 && y1 == other.y1;
    }
};

/// The smallest window holding both.
PixelWindow enclosing_window(const PixelWindow& a, const PixelWindow& b);

/// Pixels saved by rendering enclosing_window(a, b) instead of a and b:
/// area(a) + area(b) + overhead − area(union). Merge only when it is > 0.
std::int64_t merge_saving(const PixelWindow& a, const PixelWindow& b, std::int64_t overhead_pixels);

/// What rendering `windows` costs in pixels: Σ area + overhead per window.
std::int64_t windows_cost(const std::vector<PixelWindow>& windows, std::int64_t overhead_pixels);

/// The bounding box of every 8-connected cluster of non-zero pixels of a
/// `width` × `height` mask (row-major, y = 0 at the top), in the order of each
/// cluster's first pixel in row-major order.
std::vector<PixelWindow> cluster_windows(const std::uint8_t* mask, int width, int height);

/// Merges windows pairwise while some pair has merge_saving > 0 (first such
/// pair in order, repeated until no pair has): afterwards no two windows would
/// save pixels by merging. Every pixel of the input stays covered.
/// Deterministic; O(n²) per pass over n windows.
std::vector<PixelWindow> merge_windows(std::vector<PixelWindow> windows, std::int64_t overhead_pixels);

/// cluster_windows then merge_windows: the crop windows of a mask.
std::vector<PixelWindow> crop_windows(const std::uint8_t* mask, int width, int height,
                                      std::int64_t overhead_pixels);

/// A window in normalised image coordinates, 0 to 1 across the image.
struct NormalisedWindow {
    double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
};

/// Blender/Cycles' render border (border_min_x, border_max_x, border_min_y,
/// border_max_y; y = 0 at the bottom). Blender renders pixel columns
/// int(min_x·width) ≤ x < int(max_x·width) (truncation), so each edge is put a
/// quarter pixel past the window's pixel edge: truncation then gives exactly
/// the window whatever the float rounding, and so does a renderer that takes
/// the pixels whose centres lie inside. Clamped to [0, 1].
NormalisedWindow cycles_border(const PixelWindow& window, int width, int height);

/// RenderMan's crop window (xmin, xmax, ymin, ymax; y = 0 at the top). The RI
/// rule renders ceil(xres·xmin) ≤ x ≤ ceil(xres·xmax − 1), so each edge is put
/// a quarter pixel before the window's pixel edge (again exact under that
/// rule and under the pixel-centre rule). Clamped to [0, 1].
NormalisedWindow renderman_crop_window(const PixelWindow& window, int width, int height);

/// USD's dataWindowNDC as Karma (husk) takes it (xmin, ymin, xmax, ymax; y = 0
/// at the bottom): the window's exact pixel edges, which hold the centres of
/// the window's pixels with half a pixel to spare on every side.
NormalisedWindow ndc_data_window(const PixelWindow& window, int width, int height);

} // namespace modestack::refine
