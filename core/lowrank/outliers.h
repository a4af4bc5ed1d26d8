// Cleaning of a band before the SVD. NaN/Inf samples would poison the Gram sums,
// so each is replaced by its row's temporal median. Fireflies (rare huge samples
// from low-spp rendering) would each grab a mode of their own; they are clamped at
// a robust per-row threshold, and, because the design measured that plain clamping
// biases the result dark, the energy removed is spread evenly over all frames of
// the same row: the row's temporal sum (its mean over the shot) is unchanged.
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
};

/// Cleans `band` in place, row by row (rows in parallel, fixed tiles, so the result
/// is the same for any thread count): (a) each non-finite sample becomes the median
/// of the row's finite samples (0 if none); (b) each sample above the threshold is
/// clamped to it and the removed excess is added evenly to all F samples of the row.
/// Rows with nothing to change are left bit-exactly as they were. When
/// `changed_rows` is given (band.rows entries), it receives 1 for each row that
/// was changed and 0 for the others.
OutlierCounts clean_outliers(MutableBandView band, const OutlierOptions& options = {},
                             std::uint8_t* changed_rows = nullptr);

/// Cleans again, after a fresh read of the same samples, only the rows that
/// `changed_rows` marks (as clean_outliers filled it): the result is the same as
/// clean_outliers' at a fraction of the cost, since most rows have nothing to change.
void clean_marked_outliers(MutableBandView band, const OutlierOptions& options, const std::uint8_t* changed_rows);

} // namespace modestack::lowrank
