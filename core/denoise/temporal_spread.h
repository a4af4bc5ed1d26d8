// The input's spread around one frame, per pixel (docs/design.md, "Choosing an
// estimator per pixel"): what the estimator choice's per-pixel test weighs the
// input's distance from the rebuild against. Sigma's noise level is pooled
// over every frame, and the frame factor (frame_noise.h) scales it for a frame
// as a whole; but where the temporal model fails at single pixels (the edge of a
// moving hard shadow in a frame lit by a point light) the input there is far
// cleaner than either says, and the choice's window test cannot see a few
// pixels. The spread is measured where the failure is: the frame-to-frame
// differences of the input at the pixel and its two neighbours in the row over
// the K frames on one side, v̂ = the mean over those n terms of channel-mean
// (y[g+1] − y[g])²/2. That is the noise variance where the pixel's content is
// steady for K frames (slow change adds little; a change as large as the
// rebuild's error shows in the differences and keeps the test quiet). The side
// with the smaller mean is taken, so that a light that switches on just after
// the frame does not hide the frames before it. The row's pixels, not the 3×3
// around: at a shadow edge the rows above or below are across it more often
// (measured in bench/results/estimators.md, section 7).
//
// The judged frame's own sample is in the nearest difference of each side, so
// a lone bright sample (a firefly) raises the spread with it: its difference d
// is one of the n terms, d²/2 ≤ n·v̂, and a test of the input above the rebuild
// beyond √(2n) spreads (plus the margin for the neighbour's own noise) cannot
// be passed by such a sample alone.
//
// v̂ is an estimate from n terms, and at 4 spp render noise is discrete (a pixel
// in a penumbra reads the same value several frames running), so a test against
// v̂ itself fires on chance quiet: the choice tests against v̂ · spread_bound(n),
// an upper 99.9 % bound of the variance from n squared Gaussian terms
// (n / the 0.001 quantile of χ²ₙ), which is large where n is small.
#pragma once

#include "core/lowrank/confidence.h"

#include <array>
#include <cstdint>

namespace modestack::denoise {

/// Frames on each side of a frame whose differences measure its spread.
inline constexpr int kSpreadFrames = 4;
/// The most terms spread_rows gives a spread: the row's 3 pixels × one side's differences.
inline constexpr int kMostSpreadTerms = 3 * kSpreadFrames;

/// One frame's neighbourhood in time. Every plane is laid out [row][x][channel]
/// from image row `rows_begin` and must hold the rows of a call.
struct SpreadWindow {
    lowrank::ImageBandShape image;
    int rows_begin = 0;
    /// Frames f − K … f + K: index K is the judged frame (judged_samples),
    /// the others cleaned as the engine reads them; null outside the shot.
    std::array<const float*, 2 * kSpreadFrames + 1> frames{};
    /// Optionally, per pair (k, k + 1) of those frames not holding the judged
    /// one, its terms already made by spread_pair_rows over the same rows (a
    /// band shares them among its frames); null: made from `frames`. The
    /// bits are the same either way.
    std::array<const float*, 2 * kSpreadFrames> pair_terms{};
};

/// Per pixel of rows [row, end) (width values a row), one difference's term
/// channel-mean (q − p)²/2, from two frames laid out as SpreadWindow's.
void spread_pair_rows(const lowrank::ImageBandShape& image, int rows_begin, const float* p, const float* q,
                      int row, int end, float* terms);

/// The judged frame's samples for its differences: max(as read, cleaned). The
/// firefly clamp only lowers a sample and spreads what it took evenly over the
/// pixel's frames (lowrank/outliers.h), which raises every frame of the pixel
/// alike; so this is the cleaned sample, in the same terms as the cleaned
/// frames around it, where this frame was not clamped, and the sample as read
/// where it was (the firefly stays in its own differences).
void judged_samples(const float* as_read, const float* cleaned, std::int64_t samples, float* judged);

/// Per pixel of rows [row, end) (width values a row): the spread v̂ of the
/// quieter side and its number of terms n (pixels × differences); where the
/// frame has no neighbour in time, v̂ is infinite (no test) and n is 0.
/// Deterministic: a function of those samples only, summed in a fixed order.
void spread_rows(const SpreadWindow& window, int row, int end, float* spread, float* terms);

/// n over the 0.001 quantile of χ² with n degrees of freedom: the factor from
/// a variance estimated by the mean of n squared Gaussian terms to its upper
/// 99.9 % bound (n ≥ 1; kMostSpreadTerms at most from spread_rows).
double spread_bound(int terms);

} // namespace modestack::denoise
