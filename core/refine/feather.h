// Soft borders for re-rendered regions ([0089]: "overwrite the low-resolution
// values with spatial smoothing at the borders"; [0093]–[0095]). A selection is
// grown by `dilation` pixels (a low-confidence region rarely ends exactly where
// its score crosses the threshold) and then faded out over `feather` more pixels
// with a raised cosine of the Euclidean distance, so that the blend of
// re-rendered and denoised values changes gradually and no seam shows where
// their (small, different) errors meet. Every pixel with a non-zero weight must
// be re-rendered.
#pragma once

#include <cstdint>

namespace modestack::refine {

/// How far a selection grows and fades, in pixels.
struct FeatherOptions {
    int dilation = 1; ///< weight 1 up to this Euclidean distance from a selected pixel
    int feather = 3;  ///< then a raised-cosine fall to 0 over this many more pixels (plus one)
};

/// Throws a usage error when a distance is negative or above 64 pixels.
void validate_feather_options(const FeatherOptions& options);

/// Writes the blend weight of every pixel of a `width` × `height` image (row-major,
/// y = 0 at the top) from `selection` (non-zero = selected): with d the Euclidean
/// distance to the nearest selected pixel, w = 1 for d ≤ dilation,
/// w = ½(1 + cos(π (d − dilation) / (feather + 1))) up to d = dilation + feather + 1,
/// and 0 beyond. Exact distances (separable two-pass transform); parallel over
/// rows, so the result does not depend on the thread count.
void feathered_weights(const std::uint8_t* selection, int width, int height, const FeatherOptions& options,
                       float* weights);

} // namespace modestack::refine
