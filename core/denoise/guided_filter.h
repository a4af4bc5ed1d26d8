// The mode filter's cross-bilateral filter at full resolution (mode_filter.h):
// the weights of filter_weights.h, evaluated offset by offset over whole rows
// rather than window by window, so that every step is a run along x that the
// compiler vectorises, and the guide distances of an offset are computed once for
// every candidate that reaches it. Each output pixel still adds its taps in tap-row
// then column order.
#pragma once

#include "core/denoise/filter_weights.h"
#include "core/denoise/mode_filter.h"

#include <vector>

namespace modestack::denoise {

/// One coefficient image to filter: `image` the band's [y][x][c] rows, `filtered`
/// and `gains` the outputs over the valid rows ([y − valid_y0][x][c] and
/// [y − valid_y0][x]; gain Σ w² / (Σ w)², the filter's white-noise gain).
struct GuidedImage {
    FilterCandidate candidate;
    const float* image = nullptr;
    float* filtered = nullptr;
    float* gains = nullptr;
};

/// Filters every image of `images` (each candidate with width > 0 and a range or
/// feature term the guide has) over rows [valid_y0, valid_y1) of the guide's band.
void guided_filter(const Guide& guide, int valid_y0, int valid_y1, const std::vector<GuidedImage>& images);

}  // namespace modestack::denoise
