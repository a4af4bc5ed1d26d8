// Cleaning of a band before the SVD. NaN/Inf samples would poison the Gram sums,
// so each is replaced by its row's temporal median. Fireflies (rare huge samples
// from low-spp rendering) would each grab a mode of their own; they are clamped at
// a robust per-row threshold, and, because the design measured that plain clamping
// biases the result dark, the energy removed is spread evenly over all frames of
// the same row: the row's temporal sum (its mean over the shot) is unchanged.
//
// A firefly is alone in space as well as in time. Light that really comes and
// goes (a light sweeping past, a shadow leaving a wall) lifts a pixel's
// neighbours in the same frame too, and clamping it would flatten the peak into
// the pixel's other frames: a bias the rebuild's residual cannot see, since the
// cleaned input has it as well (on a shot with a light sweeping the room it was
// most of the indirect light's error). So where the rows are pixels of an image
// row (ImageRowLayout), a sample above its plain threshold is compared with a
// threshold lifted by the light its row neighbours share in that frame: the
// excess e_q = x_q,t − median_q of the two pixels on one side (the smaller of
// the two, so that one firefly beside it lifts nothing, nor a firefly that a
// renderer's pixel filter spread onto the next pixel), the larger side's (an
// edge lifts from its lit side), and 0 at least. With that shared excess S,
// the expected value is m = median + S, and the spread is the row's own
// relative spread at m's level: Monte Carlo noise scales with the light it
// samples, so a peak k times the pixel's typical value is k times as noisy.
// The threshold is m + k·1.4826·max(spread·m/typical, floor·m), never below the
// plain one. Only row neighbours (same image row, same channel) are read, so
// the result does not depend on how the shot is cut into bands. What it lets
// through, knowingly: a firefly on light its neighbours share is judged at
// that light's level, leniently where the pixel is nearly dark in most frames
// (m/typical is large); and a firefly that a wide pixel filter spread over
// three pixels or more lifts its own threshold.
#pragma once

#include "core/lowrank/band.h"

#include <cstdint>

namespace modestack::lowrank {

/// How many samples were changed.
struct OutlierCounts {
    /// NaN, +Inf or −Inf samples replaced.
    std::int64_t non_finite = 0;
    /// Samples above the firefly threshold that were clamped.
    std::int64_t fireflies = 0;
};

/// Knobs of clean_outliers.
struct OutlierOptions {
    /// Treat fireflies (false: only replace NaN/Inf).
    bool fireflies = true;
    /// Threshold median_t + k·1.4826·MAD_t (1.4826·MAD estimates a Gaussian σ).
    double firefly_k = 6.0;
    /// Lower bound of the MAD as a fraction of the row's median |x| (a median, so that
    /// the firefly itself cannot raise it): a near-constant row has MAD ≈ 0, and rounding
    /// wiggles would count as fireflies without it. A row that is 0 in more than half of
    /// its frames keeps threshold ≈ 0: all its lit samples are spread evenly over the
    /// frames, i.e. replaced by the row's temporal mean, which keeps their energy.
    double mad_floor_fraction = 0.1;
    /// Judge each frame at its own noise level, where the rows are pixels of an
    /// image row (ImageRowLayout): a frame's scale s_t is the median |x − (left
    /// + right)/2| of the image row's samples in that frame, as read, over the
    /// mean of those medians over the frames (at least kLeastFrameScale). The
    /// threshold of frame t is median + k·1.4826·max(s_t·MAD, floor), the MAD
    /// that of (x − median)/s. With one threshold for every frame, the ordinary
    /// upper samples of a few noisy frames (a large light switched on) read as
    /// fireflies, and their excess, spread evenly, brightened every clean frame
    /// and darkened the noisy ones. The excess is still spread evenly: given
    /// back in proportion to s_t it measured worse (bench/results/estimators.md,
    /// section 24). False, or rows that are not pixels: one threshold.
    bool per_frame_noise = true;
};

/// The least frame scale of the per-frame threshold: a frame far quieter than
/// the shot's mean (a black frame) is judged at 1/8 of the mean noise.
inline constexpr double kLeastFrameScale = 0.125;

/// How a band's rows lie in the image: `channels` consecutive rows are one pixel's
/// channels and width·channels consecutive rows one image row, from the band's
/// first row. Width 0: the rows are not pixels (no neighbours, plain thresholds).
struct ImageRowLayout {
    int width = 0;
    int channels = 0;
};

/// Cleans `band` in place, row by row (image rows in parallel, each on its own,
/// so the result is the same for any thread count): (a) each non-finite sample becomes the median
/// of the row's finite samples (0 if none); (b) each sample above the threshold is
/// clamped to it and the removed excess is added evenly to all F samples of the row.
/// Rows with nothing to change are left bit-exactly as they were. When
/// `changed_rows` is given (band.rows entries), it receives 1 for each row that
/// was changed and 0 for the others. With a `layout` the band must be whole image
/// rows (modestack::Error, internal, otherwise).
OutlierCounts clean_outliers(MutableBandView band, const OutlierOptions& options = {},
                             std::uint8_t* changed_rows = nullptr, const ImageRowLayout& layout = {});

/// Cleans again, after a fresh read of the same samples, only the rows that
/// `changed_rows` marks (as clean_outliers filled it, with the same layout): the
/// result is the same as clean_outliers' at a fraction of the cost, since most
/// rows have nothing to change.
void clean_marked_outliers(MutableBandView band, const OutlierOptions& options,
                           const std::uint8_t* changed_rows, const ImageRowLayout& layout = {});

} // namespace modestack::lowrank
