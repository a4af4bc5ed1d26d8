// The rebuild's lasting misfit at a pixel (docs/design.md, "Choosing an
// estimator per pixel"). The window tests judge a frame's pixels together, so a
// misfit of single pixels scores little there; the spread test
// (temporal_spread.h) judges one pixel against the input's spread, and its
// bound must cover its few terms and any firefly, so it fires only many noise
// widths out. But where the rebuild is wrong for a reason that lasts (modes
// fitted to the noise of far noisier frames carry it into clean ones as a
// fixed pattern: bench/results/estimators.md, section 22) its residual input −
// rebuild keeps its sign and size from frame to frame, while the noise does
// not. Per side of the frame (before: frames t − K … t; after: t … t + K, so
// that a light switched on just after does not hide the frames before), the
// test is Student's t of the pixel's mean residual over that side's frames,
// with the scatter of the residuals about each pixel's own mean pooled over
// the pixel and its two row neighbours (the misfit may change from pixel to
// pixel, the noise level hardly does): t = mean·√n / s with n the pixel's
// frames and s² the pooled scatter, 3·(n − 1) degrees of freedom (2·(n − 1) at
// the image's first and last column). Render noise is independent from frame
// to frame with a seed that changes per frame; noise that repeats mostly stays
// in the rebuild, and where it is not counted the part left in the residual
// lasts too (a fixed-seed shot's direct light: 6 % of its pixels changed, the
// shot's error the same, bench/results/estimators.md, section 22).
//
// A side fires beyond the two-sided 0.5·10⁻⁴ quantile of t (both sides: 10⁻⁴
// of the pixels of a shot the rebuild fits). A lone firefly in the pixel's
// frames raises s with the mean: t ≈ 1.7 for one sample among five. But 4-spp
// indirect light is heavy-tailed and its bright paths can come back a few
// frames running, so a run of high samples can pass where the rebuild was
// right (it cost a benchmark shot's indirect light 2 %). The input is therefore
// taken only where the engine's own sigma² of the rebuild (its channel mean) is
// at least s² (of the channel-mean residual): the rebuild rates itself no
// better than the input's scatter, and the test shows that its error is real.
// Render noise is much alike in a pixel's channels, so the two are alike; for
// noise independent between channels s² would be a third of a channel's and
// the gate that much looser. Where the rebuild is sure of itself (sigma far
// below the input's noise: the indirect light almost everywhere) the test is
// not asked. A residual that does not scatter and is not 0 passes wherever
// the rebuild's sigma is not below it: a noise-free input the rebuild misses.
//
// The judged frame's sample is the input as read (as the choice's risks see
// it); the frames around are the engine's cleaned frames and their rebuilds.
#pragma once

#include "core/denoise/temporal_spread.h"
#include "core/lowrank/confidence.h"

#include <array>

namespace modestack::denoise {

/// Frames on each side of a frame whose residuals the test pools (the spread's).
inline constexpr int kMisfitFrames = kSpreadFrames;
/// The most degrees of freedom of a side's scatter: its row's 3 pixels × (frames − 1).
inline constexpr int kMostMisfitFreedom = 3 * kMisfitFrames;
/// Values per pixel misfit_rows gives: per side (before, after) the pixel's
/// mean residual, the pooled scatter s², the pixel's frames n and the degrees
/// of freedom of s².
inline constexpr int kMisfitValues = 8;

/// One frame's neighbourhood in time. Every plane is laid out [row][x][channel]
/// from image row `rows_begin` and must hold the rows of a call; index
/// kMisfitFrames is the judged frame (its input as read, its rebuild); null
/// outside the shot.
struct MisfitWindow {
    lowrank::ImageBandShape image;
    int rows_begin = 0;
    std::array<const float*, 2 * kMisfitFrames + 1> input{}, rebuilt{};
};

/// Per pixel of rows [row, end) (width × kMisfitValues values a row): each
/// side's residual statistics (see above), channel means; a side without two
/// frames has 0 degrees of freedom. Deterministic: a function of those samples
/// only, summed in a fixed order.
void misfit_rows(const MisfitWindow& window, int row, int end, float* misfit);

/// Whether either side of a pixel's statistics (kMisfitValues values) shows a
/// lasting misfit, asked only where the rebuild's own variance (its sigma²,
/// channel mean) is at least that side's scatter s².
bool lasting_misfit(const float* misfit, double rebuilt_variance);

/// The two-sided 0.5·10⁻⁴ quantile of Student's t with `freedom` ≥ 1 degrees of freedom.
double misfit_limit(int freedom);

} // namespace modestack::denoise
