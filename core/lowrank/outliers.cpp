#include "core/lowrank/outliers.h"

#include "core/lowrank/row_median.h"
#include "core/lowrank/tiles.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace modestack::lowrank {
namespace {

// Scratch for one row.
struct RowScratch {
    std::vector<double> row;
    std::vector<double> to_median;  // the finite samples, |samples| or deviations a median is taken of
    std::vector<double> select_a, select_b;  // row_median's work space

    void resize(std::size_t frames)
    {
        for (std::vector<double>* buffer : {&row, &to_median, &select_a, &select_b})
            buffer->resize(frames);
    }
    double median(const std::vector<double>& values, std::size_t count)
    {
        return row_median(values.data(), count, select_a.data(), select_b.data());
    }
};

// Clamps the fireflies of scratch.row (see outliers.h); true when it changed it.
bool clamp_fireflies(RowScratch& scratch, const OutlierOptions& options, OutlierCounts& counts)
{
    const std::size_t frames = scratch.row.size();
    const double median = scratch.median(scratch.row, frames);
    const auto [lowest, highest] = std::minmax_element(scratch.row.begin(), scratch.row.end());
    // The median of |x|: for a row with no negative value (radiance) that is the median.
    double typical_magnitude = median;
    if (*lowest < 0.0) {
        for (std::size_t t = 0; t < frames; ++t)
            scratch.to_median[t] = std::abs(scratch.row[t]);
        typical_magnitude = scratch.median(scratch.to_median, frames);
    }
    const double floor_spread = std::max(options.mad_floor_fraction * typical_magnitude, 1e-30);
    const auto threshold_of = [&](double mad) {
        return median + options.firefly_k * 1.4826 * std::max(mad, floor_spread);
    };
    // Most rows have no firefly, and the threshold only grows with the MAD (as
    // does its rounding): once some D ≤ MAD gives a threshold at or above the
    // largest sample, the row is clean without the MAD's median. D is the spread
    // that would put the threshold at the largest sample; D ≤ MAD when fewer than
    // half of the deviations lie below D.
    if (*highest <= threshold_of(0.0))
        return false;
    std::size_t below = 0;
    const double enough = (*highest - median) / (options.firefly_k * 1.4826);
    for (std::size_t t = 0; t < frames; ++t) {
        scratch.to_median[t] = std::abs(scratch.row[t] - median);
        below += scratch.to_median[t] < enough ? 1 : 0;
    }
    if (below < (frames + 1) / 2 && *highest <= threshold_of(enough))
        return false;
    const double mad = scratch.median(scratch.to_median, frames);
    const double threshold = threshold_of(mad);
    double excess = 0;
    for (double& value : scratch.row)
        if (value > threshold) {
            excess += value - threshold;
            value = threshold;
            ++counts.fireflies;
        }
    if (excess <= 0)
        return false;
    const double share = excess / static_cast<double>(frames);
    for (double& value : scratch.row)
        value += share;
    return true;
}

// Cleans row i of the band, whose F samples `values` holds contiguously.
OutlierCounts clean_row(const MutableBandView& band, std::int64_t i, const float* values,
                        const OutlierOptions& options, RowScratch& scratch, bool* changed_out = nullptr)
{
    OutlierCounts counts;
    const int frames = band.frames;
    std::size_t finite = 0;
    for (int t = 0; t < frames; ++t) {
        const double value = values[t];
        scratch.row[static_cast<std::size_t>(t)] = value;
        if (std::isfinite(value))
            scratch.to_median[finite++] = value;
    }
    bool changed = false;
    if (finite < static_cast<std::size_t>(frames)) {
        const double median = scratch.median(scratch.to_median, finite);
        for (double& value : scratch.row)
            if (!std::isfinite(value)) {
                value = median;
                ++counts.non_finite;
            }
        changed = true;
    }
    if (options.fireflies && frames >= 3 && clamp_fireflies(scratch, options, counts))
        changed = true;
    if (changed_out)
        *changed_out = changed;
    if (changed)
        for (int t = 0; t < frames; ++t)
            band.at(i, t) = static_cast<float>(scratch.row[static_cast<std::size_t>(t)]);
    return counts;
}

} // namespace

OutlierCounts clean_outliers(MutableBandView band, const OutlierOptions& options, std::uint8_t* changed_rows)
{
    if (band.rows <= 0 || band.frames <= 0)
        return {};
    const std::int64_t tiles = tile_count(band.rows);
    std::vector<OutlierCounts> per_tile(static_cast<std::size_t>(tiles));
    for_each_tile(band.rows, [&](std::int64_t row0, std::int64_t count) {
        RowScratch scratch;
        scratch.resize(static_cast<std::size_t>(band.frames));
        OutlierCounts& tile_counts = per_tile[static_cast<std::size_t>(row0 / kTileRows)];
        // The rows are gathered kGatherRows at a time into [row][frame], one short
        // contiguous read per frame, rather than F reads F pages apart for each row.
        constexpr std::int64_t kGatherRows = 64;
        std::vector<float> gathered(static_cast<std::size_t>(kGatherRows * band.frames));
        for (std::int64_t first = row0; first < row0 + count; first += kGatherRows) {
            const std::int64_t rows = std::min(kGatherRows, row0 + count - first);
            for (int t = 0; t < band.frames; ++t) {
                const float* frame_rows = &band.at(first, t);
                for (std::int64_t r = 0; r < rows; ++r)
                    gathered[static_cast<std::size_t>(r * band.frames + t)] = frame_rows[r];
            }
            for (std::int64_t r = 0; r < rows; ++r) {
                bool changed = false;
                const OutlierCounts row_counts = clean_row(
                    band, first + r, gathered.data() + r * band.frames, options, scratch, &changed);
                tile_counts.non_finite += row_counts.non_finite;
                tile_counts.fireflies += row_counts.fireflies;
                if (changed_rows)
                    changed_rows[first + r] = changed ? 1 : 0;
            }
        }
    });
    OutlierCounts total;
    for (const OutlierCounts& counts : per_tile) {
        total.non_finite += counts.non_finite;
        total.fireflies += counts.fireflies;
    }
    return total;
}

void clean_marked_outliers(MutableBandView band, const OutlierOptions& options, const std::uint8_t* changed_rows)
{
    if (band.rows <= 0 || band.frames <= 0)
        return;
    for_each_tile(band.rows, [&](std::int64_t row0, std::int64_t count) {
        RowScratch scratch;
        std::vector<float> values;  // the row's samples, contiguous
        for (std::int64_t i = row0; i < row0 + count; ++i) {
            if (!changed_rows[i])
                continue;
            if (scratch.row.empty()) {
                scratch.resize(static_cast<std::size_t>(band.frames));
                values.resize(static_cast<std::size_t>(band.frames));
            }
            for (int t = 0; t < band.frames; ++t)
                values[static_cast<std::size_t>(t)] = band.at(i, t);
            clean_row(band, i, values.data(), options, scratch);
        }
    });
}

} // namespace modestack::lowrank
