// The input's spread around one frame, per pixel (docs/design.md, "Choosing an
// estimator per pixel"): what the estimator choice's per-pixel test weighs the
// input's distance from the rebuild against. Sigma's noise level is pooled
// over every frame, and the frame factor (frame_noise.h) scales it for a frame
// as a whole; but where the temporal model fails at single pixels (the edge of a
// moving hard shadow in a frame lit by a point light) the input there is far
// cleaner than either says, and the choice's window test cannot see a few
// pixels. The spread is measured where the failure is: the frame-to-frame
// differences d of the input at the pixel and its two neighbours in the row over
// the K frames on one side, two ways:
//  - Steady: per pixel, channel-mean Σd²/2 over the side's m differences, whose
//    mean is m·v for white noise of variance v; v̂ is the row's 3 sums over 3·m.
//    The noise variance where the pixel's content holds still.
//  - Trend: the same less the side's own trend, Σ(d − d̄)²/2, whose mean is
//    (m − 1/m)·v with m − 1 degrees of freedom; v̂ is the row's sums over
//    3·(m − 1/m). The noise variance where the content changes evenly: a light
//    that moves lights a wall more each frame, and Steady counts that slope as
//    noise (it hid a rebuild 0.1 off a clean 0.3, bench/results/estimators.md,
//    section 20). It has a degree of freedom less per pixel, so where the
//    content holds still its bound below is the looser one.
// Each is a bound of the noise where its model holds and too large, so on the
// safe side, where the content changes otherwise; the choice tests against both
// and the input is taken when either fires. A change as large as the rebuild's
// error that keeps neither model shows in the differences and keeps the test
// quiet. Per estimate, the side with the smaller v̂ is taken, so that a light
// that switches on just after the frame does not hide the frames before it.
// The row's pixels, not the 3×3 around: at a shadow edge the rows above or
// below are across it more often (measured in bench/results/estimators.md,
// section 7).
//
// The judged frame's own sample is in the nearest difference of each side, so
// a lone bright sample (a firefly) raises the spread with it: its difference d
// is one of Steady's n terms, d²/2 ≤ n·v̂; a sample d above the side's trend
// adds at least d²(1 − 1/m)/2 to its pixel's Trend sum, so d² ≤ 2·p·(m + 1)·v̂
// over p pixels, at most 2·(n + 6)·v̂ with n = p·(m − 1). A test of the input
// above the rebuild beyond that reach (lone_sample_reach) plus the margin for
// the neighbours' own noise cannot be passed by such a sample alone.
//
// v̂ is an estimate from n terms (degrees of freedom), and at 4 spp render
// noise is discrete (a pixel in a penumbra reads the same value several frames
// running), so a test against v̂ itself fires on chance quiet: the choice tests
// against v̂ · spread_bound(n), an upper 99.9 % bound of the variance from n
// squared Gaussian terms (n / the 0.001 quantile of χ²ₙ), which is large where
// n is small.
#pragma once

#include "core/lowrank/confidence.h"

#include <array>
#include <cstdint>

namespace modestack::denoise {

/// Frames on each side of a frame whose differences measure its spread.
inline constexpr int kSpreadFrames = 4;
/// The most terms spread_rows gives a spread: the row's 3 pixels × one side's differences.
inline constexpr int kMostSpreadTerms = 3 * kSpreadFrames;

/// The two ways the spread is measured (see above); spread_rows gives both
/// per pixel, in this order.
enum class SpreadEstimate { Steady = 0, Trend = 1 };
inline constexpr int kSpreadEstimates = 2;

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

/// Per pixel of rows [row, end) (width pixels a row, kSpreadEstimates values a
/// pixel, SpreadEstimate's order): the spread v̂ of the quieter side and its
/// number of terms n (pixels × differences; Trend: × (differences − 1), and a
/// side needs two). Where the frame has no such side, v̂ is infinite (no test)
/// and n is 0. Deterministic: a function of those samples only, summed in a
/// fixed order.
void spread_rows(const SpreadWindow& window, int row, int end, float* spread, float* terms);

/// How many spreads a lone bright sample in the judged frame can stand above
/// its side (Steady: √(2n)) or above its side's trend (Trend: √(2·(n + 6)),
/// exact for the row's 3 pixels, an upper bound at the image's first and last
/// column), for a spread of n ≥ 1 terms.
double lone_sample_reach(SpreadEstimate estimate, int terms);

/// n over the 0.001 quantile of χ² with n degrees of freedom: the factor from
/// a variance estimated by the mean of n squared Gaussian terms to its upper
/// 99.9 % bound (n ≥ 1; kMostSpreadTerms at most from spread_rows).
double spread_bound(int terms);

} // namespace modestack::denoise
