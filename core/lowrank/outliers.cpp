#include "core/lowrank/outliers.h"

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/lowrank/row_median.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace modestack::lowrank {
namespace {

constexpr double kNoClamp = std::numeric_limits<double>::infinity();
// The shared excess reads this many pixels on each side of a sample.
constexpr std::int64_t kNeighbourPixels = 2;

// What the first look at one row found.
struct RowStats {
    double median = 0;           // of the row, its non-finite samples replaced
    double fill = 0;             // what a non-finite sample becomes: the median of the finite ones
    double typical = 0;          // the median of |x|
    double spread = 0;           // max(MAD, floor): the plain threshold's spread (per-frame scales: the MAD)
    double threshold = kNoClamp; // the plain threshold (at scale 1); kNoClamp: no sample above it
    double floor = 0;            // per-frame scales: the spread's floor (spread is then the scaled MAD)
    std::int64_t non_finite = 0; // samples replaced
};

// Scratch for one group of rows.
struct GroupScratch {
    std::vector<float> values; // the group's samples as read, [row][frame]
    // The previous piece of the same image row: its samples as read, from band
    // row previous_first (it may have cleaned some of them in the band since).
    std::vector<float> previous;
    std::int64_t previous_first = 0, previous_rows = 0;
    std::vector<RowStats> stats;
    std::vector<double> row;
    std::vector<double> to_median; // the finite samples, |samples| or deviations a median is taken of
    std::vector<double> select_a, select_b; // row_median's work space
    // Per frame, its noise scale along this image row (OutlierOptions::
    // per_frame_noise); empty: one threshold for every frame.
    std::vector<double> scale;
    std::vector<float> high_pass; // one frame's |high-pass| samples, for their median

    void resize(std::size_t rows, std::size_t frames)
    {
        values.resize(rows * frames);
        stats.resize(rows);
        for (std::vector<double>* buffer : {&row, &to_median, &select_a, &select_b})
            buffer->resize(frames);
    }
    double median(const std::vector<double>& of, std::size_t count)
    {
        return row_median(of.data(), count, select_a.data(), select_b.data());
    }
    const float* samples(std::int64_t r) const { return &values[static_cast<std::size_t>(r) * row.size()]; }
};

// Sample t of row r as the cleaning sees it: a non-finite one is the row's fill.
double sample_or_fill(const GroupScratch& scratch, std::int64_t r, std::size_t t, const RowStats& stats)
{
    const float value = scratch.samples(r)[t];
    return std::isfinite(value) ? value : stats.fill;
}

// Loads row r into scratch.row as the cleaning sees it.
void load(GroupScratch& scratch, std::int64_t r, const RowStats& stats)
{
    for (std::size_t t = 0; t < scratch.row.size(); ++t)
        scratch.row[t] = sample_or_fill(scratch, r, t, stats);
}

// Counts row r's non-finite samples and finds its fill, the median of the
// finite ones (0 if none), into `stats`; then loads the row.
void first_load(GroupScratch& scratch, std::int64_t r, RowStats& stats)
{
    const float* values = scratch.samples(r);
    const std::size_t frames = scratch.row.size();
    std::size_t finite = 0;
    for (std::size_t t = 0; t < frames; ++t)
        if (std::isfinite(values[t]))
            scratch.to_median[finite++] = values[t];
    stats.non_finite = static_cast<std::int64_t>(frames - finite);
    if (stats.non_finite > 0)
        stats.fill = scratch.median(scratch.to_median, finite);
    load(scratch, r, stats);
}

// row_statistics' firefly check with each frame judged at its own scale s_t
// (outliers.h, per_frame_noise): frame t's threshold is median +
// k·1.4826·max(s_t·MAD, floor), the MAD that of the deviations (x_t − median)/s_t.
// The floor only raises thresholds, so the shortcuts of the plain check hold.
void scaled_statistics(GroupScratch& scratch, const OutlierOptions& options, double floor_spread,
                       RowStats& stats)
{
    const std::size_t frames = scratch.row.size();
    const double median = stats.median, reach = options.firefly_k * 1.4826;
    double highest = -std::numeric_limits<double>::infinity(), highest_scaled = highest;
    for (std::size_t t = 0; t < frames; ++t) {
        highest = std::max(highest, scratch.row[t] - median);
        highest_scaled = std::max(highest_scaled, (scratch.row[t] - median) / scratch.scale[t]);
    }
    if (highest <= reach * floor_spread)
        return;
    // The MAD that would put the highest scaled deviation at its threshold:
    // when fewer than half of the deviations lie below it, the MAD is larger.
    std::size_t below = 0;
    const double enough = highest_scaled / reach;
    for (std::size_t t = 0; t < frames; ++t) {
        scratch.to_median[t] = std::abs(scratch.row[t] - median) / scratch.scale[t];
        below += scratch.to_median[t] < enough ? 1 : 0;
    }
    if (below < (frames + 1) / 2)
        return;
    const double mad = scratch.median(scratch.to_median, frames);
    bool above = false;
    for (std::size_t t = 0; t < frames && !above; ++t)
        above = scratch.row[t] - median > reach * std::max(mad * scratch.scale[t], floor_spread);
    if (!above)
        return;
    stats.spread = mad;
    stats.floor = floor_spread;
    stats.threshold = median + reach * std::max(mad, floor_spread); // at scale 1: marks a row to clean
}

// The median of scratch.row (NaN/Inf replaced) and, when a firefly check is
// asked, the plain threshold median_t + k·1.4826·max(MAD_t, floor) if some sample
// lies above it (outliers.h).
void row_statistics(GroupScratch& scratch, const OutlierOptions& options, bool check, RowStats& stats)
{
    const std::size_t frames = scratch.row.size();
    const double median = stats.median = scratch.median(scratch.row, frames);
    if (!check)
        return;
    const auto [lowest, highest] = std::minmax_element(scratch.row.begin(), scratch.row.end());
    // The median of |x|: for a row with no negative value (radiance) that is the median.
    double typical_magnitude = median;
    if (*lowest < 0.0) {
        for (std::size_t t = 0; t < frames; ++t)
            scratch.to_median[t] = std::abs(scratch.row[t]);
        typical_magnitude = scratch.median(scratch.to_median, frames);
    }
    stats.typical = typical_magnitude;
    const double floor_spread = std::max(options.mad_floor_fraction * typical_magnitude, 1e-30);
    if (!scratch.scale.empty()) {
        scaled_statistics(scratch, options, floor_spread, stats);
        return;
    }
    const auto threshold_of = [&](double mad) {
        return median + options.firefly_k * 1.4826 * std::max(mad, floor_spread);
    };
    // Most rows have no firefly, and the threshold only grows with the MAD (as
    // does its rounding): once some D ≤ MAD gives a threshold at or above the
    // largest sample, the row is clean without the MAD's median. D is the spread
    // that would put the threshold at the largest sample; D ≤ MAD when fewer than
    // half of the deviations lie below D.
    if (*highest <= threshold_of(0.0))
        return;
    std::size_t below = 0;
    const double enough = (*highest - median) / (options.firefly_k * 1.4826);
    for (std::size_t t = 0; t < frames; ++t) {
        scratch.to_median[t] = std::abs(scratch.row[t] - median);
        below += scratch.to_median[t] < enough ? 1 : 0;
    }
    if (below < (frames + 1) / 2 && *highest <= threshold_of(enough))
        return;
    const double mad = scratch.median(scratch.to_median, frames);
    if (*highest <= threshold_of(mad))
        return;
    stats.spread = std::max(mad, floor_spread);
    stats.threshold = threshold_of(mad);
}

// Geometry of one group: consecutive rows, read whole, of which rows
// [own_begin, own_end) are cleaned; with `channels`, they are pixels of one
// image row (`channels` interleaved channels) and the rows beyond the own ones
// are the row neighbours the own ones need, as far as the image row goes.
struct GroupShape {
    std::int64_t rows = 0;
    int frames = 0;
    int channels = 0; // 0: the rows are not pixels of an image row
    std::int64_t own_begin = 0, own_end = 0;
};

// How far sample (r, t) of the group stands above its median where its row
// neighbours all stand above theirs: the light they share in frame t (outliers.h).
double shared_excess(const GroupScratch& scratch, const GroupShape& shape, std::int64_t r, int t)
{
    const auto excess = [&](std::int64_t q) {
        if (q < 0 || q >= shape.rows)
            return -kNoClamp;
        const RowStats& stats = scratch.stats[static_cast<std::size_t>(q)];
        return sample_or_fill(scratch, q, static_cast<std::size_t>(t), stats) - stats.median;
    };
    const std::int64_t c = shape.channels;
    const double left = std::min(excess(r - c), excess(r - 2 * c));
    const double right = std::min(excess(r + c), excess(r + 2 * c));
    return std::max({left, right, 0.0});
}

// The samples a frame's scale along an image row is the median of, about.
constexpr std::int64_t kScaleSamples = 1024;

// Each frame's noise scale along one image row (OutlierOptions::
// per_frame_noise): the median |x − (left + right)/2| of the row's samples as
// read in that frame (every pixel's, or every step-th's on a long row), over the mean of those medians, at
// least kLeastFrameScale; all 1 where every median is 0. A median, so that the fireflies being judged do not
// raise it; the whole image row, so that a frame's scale does not hang on the few pixels of one piece.
void image_row_frame_scales(const MutableBandView& band, std::int64_t first, const ImageRowLayout& layout,
                            GroupScratch& scratch)
{
    const int frames = band.frames;
    const std::int64_t c = layout.channels, samples = static_cast<std::int64_t>(layout.width) * c;
    // Every step-th pixel: about kScaleSamples samples are plenty for a median
    // (a film frame's row holds 5,760).
    const std::int64_t step = std::max<std::int64_t>(1, samples / kScaleSamples);
    scratch.scale.assign(static_cast<std::size_t>(frames), 1.0);
    double sum = 0;
    for (int t = 0; t < frames; ++t) {
        scratch.high_pass.clear();
        const float* row = &band.at(first, t);
        for (std::int64_t pixel = 1; pixel + 1 < layout.width; pixel += step)
            for (std::int64_t i = pixel * c; i < (pixel + 1) * c; ++i) {
                const double d =
                    static_cast<double>(row[i]) - 0.5 * (static_cast<double>(row[i - c]) + row[i + c]);
                if (std::isfinite(d))
                    scratch.high_pass.push_back(static_cast<float>(std::abs(d)));
            }
        double median = 0;
        if (!scratch.high_pass.empty()) {
            const auto middle =
                scratch.high_pass.begin() + static_cast<std::ptrdiff_t>(scratch.high_pass.size() / 2);
            std::nth_element(scratch.high_pass.begin(), middle, scratch.high_pass.end());
            median = *middle;
        }
        scratch.scale[static_cast<std::size_t>(t)] = median;
        sum += median;
    }
    if (!(sum > 0)) {
        std::fill(scratch.scale.begin(), scratch.scale.end(), 1.0);
        return;
    }
    const double mean = sum / frames;
    for (double& scale : scratch.scale)
        scale = std::max(scale / mean, kLeastFrameScale);
}

// The plain threshold's spread in frame t: the row's, at the frame's noise
// scale where there are scales.
double frame_spread(const RowStats& stats, const GroupScratch& scratch, int t)
{
    if (scratch.scale.empty())
        return stats.spread;
    return std::max(stats.spread * scratch.scale[static_cast<std::size_t>(t)], stats.floor);
}

// The plain threshold of frame t, at its noise scale where there are scales.
double frame_threshold(const RowStats& stats, const OutlierOptions& options, const GroupScratch& scratch,
                       int t)
{
    if (scratch.scale.empty())
        return stats.threshold;
    return stats.median + options.firefly_k * 1.4826 * frame_spread(stats, scratch, t);
}

// The threshold of sample t of a row with a plain threshold, lifted by the light
// its neighbours share in that frame, the spread scaled to that light's level
// (and to the frame's noise scale).
double lifted_threshold(const RowStats& stats, const OutlierOptions& options, const GroupScratch& scratch,
                        int t, double shared)
{
    if (!(shared > 0))
        return frame_threshold(stats, options, scratch, t);
    const double expected = stats.median + shared;
    const double level = stats.typical > 0 && expected > stats.typical ? expected / stats.typical : 1.0;
    const double spread =
        std::max(frame_spread(stats, scratch, t) * level, options.mad_floor_fraction * std::abs(expected));
    return expected + options.firefly_k * 1.4826 * spread;
}

// Cleans the group's rows [first, first + shape.rows) of `band` (only those
// `only` marks, when given); returns what it changed and marks `changed_rows`.
OutlierCounts clean_group(const MutableBandView& band, std::int64_t first, const GroupShape& shape,
                          const OutlierOptions& options, const std::uint8_t* only, std::uint8_t* changed_rows,
                          GroupScratch& scratch)
{
    OutlierCounts counts;
    const std::int64_t rows = shape.rows;
    const int frames = shape.frames;
    const auto cleaned = [&](std::int64_t r) {
        return r >= shape.own_begin && r < shape.own_end && (only == nullptr || only[first + r] != 0);
    };
    const bool fireflies = options.fireflies && frames >= 3;
    const std::int64_t reach = fireflies ? kNeighbourPixels * shape.channels : 0;
    // Rows whose statistics are needed: those cleaned and, for the shared
    // excess, their row neighbours.
    const auto needed = [&](std::int64_t r) {
        for (std::int64_t q = std::max<std::int64_t>(0, r - reach); q <= std::min(rows - 1, r + reach); ++q)
            if (cleaned(q))
                return true;
        return false;
    };
    bool any = false;
    for (std::int64_t r = shape.own_begin; r < shape.own_end && !any; ++r)
        any = cleaned(r);
    if (!any) {
        scratch.previous_rows = 0; // nothing cleaned here: the next piece reads the band as it is
        return counts;
    }
    scratch.resize(static_cast<std::size_t>(rows), static_cast<std::size_t>(frames));
    // [row][frame]: one short contiguous read per frame rather than F reads F pages apart for each row.
    for (int t = 0; t < frames; ++t) {
        const float* frame_rows = &band.at(first, t);
        for (std::int64_t r = 0; r < rows; ++r)
            scratch.values[static_cast<std::size_t>(r * frames + t)] = frame_rows[r];
    }
    // Neighbours the previous piece owned are read as they were, not as it cleaned them.
    for (std::int64_t r = 0; r < shape.own_begin; ++r) {
        const std::int64_t before = first + r - scratch.previous_first;
        if (before >= 0 && before < scratch.previous_rows)
            std::copy_n(&scratch.previous[static_cast<std::size_t>(before * frames)], frames,
                        &scratch.values[static_cast<std::size_t>(r * frames)]);
    }
    for (std::int64_t r = 0; r < rows; ++r) {
        RowStats& stats = scratch.stats[static_cast<std::size_t>(r)];
        stats = {};
        if (!needed(r))
            continue;
        first_load(scratch, r, stats);
        if (fireflies)
            row_statistics(scratch, options, cleaned(r), stats);
    }
    for (std::int64_t r = shape.own_begin; r < shape.own_end; ++r) {
        if (!cleaned(r))
            continue;
        const RowStats& stats = scratch.stats[static_cast<std::size_t>(r)];
        counts.non_finite += stats.non_finite;
        bool changed = stats.non_finite > 0;
        if (changed || stats.threshold != kNoClamp)
            load(scratch, r, stats);
        if (stats.threshold != kNoClamp) {
            double excess = 0;
            for (int t = 0; t < frames; ++t) {
                double& value = scratch.row[static_cast<std::size_t>(t)];
                if (!(value > frame_threshold(stats, options, scratch, t)))
                    continue;
                const double threshold =
                    shape.channels > 0
                        ? lifted_threshold(stats, options, scratch, t, shared_excess(scratch, shape, r, t))
                        : stats.threshold;
                if (value > threshold) {
                    excess += value - threshold;
                    value = threshold;
                    ++counts.fireflies;
                }
            }
            if (excess > 0) {
                const double share = excess / static_cast<double>(frames);
                for (double& value : scratch.row)
                    value += share;
                changed = true;
            }
        }
        if (changed_rows)
            changed_rows[first + r] = changed ? 1 : 0;
        if (changed)
            for (int t = 0; t < frames; ++t)
                band.at(first + r, t) = static_cast<float>(scratch.row[static_cast<std::size_t>(t)]);
    }
    std::swap(scratch.previous, scratch.values);
    scratch.previous_first = first;
    scratch.previous_rows = rows;
    return counts;
}

// Runs clean_group over the band's groups in parallel: pieces of image rows
// (with their row neighbours) when `layout` has a width, otherwise fixed runs
// of rows with no neighbours. A piece, not a whole image row, so that the
// scratch stays small on long shots (an image row of 1080p over 1000 frames is
// 23 MB); the neighbours it reads twice cost a few % more medians.
OutlierCounts clean_groups(const MutableBandView& band, const OutlierOptions& options,
                           const ImageRowLayout& layout, const std::uint8_t* only, std::uint8_t* changed_rows)
{
    if (band.rows <= 0 || band.frames <= 0)
        return {};
    constexpr std::int64_t kLoneRows = 64, kPiecePixels = 128;
    const bool pixels = layout.width > 0;
    const std::int64_t row_samples = pixels ? static_cast<std::int64_t>(layout.width) * layout.channels : 0;
    if (layout.width < 0 || (pixels && (layout.channels <= 0 || band.rows % row_samples != 0)))
        throw Error(ErrorKind::Internal, "clean_outliers: the band is not whole image rows of its layout");
    const std::int64_t pieces_per_row = pixels ? (layout.width + kPiecePixels - 1) / kPiecePixels : 1;
    const std::int64_t groups =
        pixels ? band.rows / row_samples * pieces_per_row : (band.rows + kLoneRows - 1) / kLoneRows;
    const auto shape_of = [&](std::int64_t g, std::int64_t& first) {
        GroupShape shape;
        shape.frames = band.frames;
        if (!pixels) {
            first = g * kLoneRows;
            shape.rows = shape.own_end = std::min(kLoneRows, band.rows - first);
            return shape;
        }
        const std::int64_t image_row = g / pieces_per_row, x0 = g % pieces_per_row * kPiecePixels;
        const std::int64_t x1 = std::min<std::int64_t>(layout.width, x0 + kPiecePixels);
        const std::int64_t read0 = std::max<std::int64_t>(0, x0 - kNeighbourPixels),
                           read1 = std::min<std::int64_t>(layout.width, x1 + kNeighbourPixels);
        first = image_row * row_samples + read0 * layout.channels;
        shape.channels = layout.channels;
        shape.rows = (read1 - read0) * layout.channels;
        shape.own_begin = (x0 - read0) * layout.channels;
        shape.own_end = (x1 - read0) * layout.channels;
        return shape;
    };
    // Each frame judged at its own scale along the image row, measured on the
    // row as read before any piece cleans it; only for rows something cleans.
    const bool scaled = pixels && options.per_frame_noise && options.fireflies && band.frames >= 3;
    const auto row_is_cleaned = [&](std::int64_t image_row) {
        if (only == nullptr)
            return true;
        const std::uint8_t* marks = only + image_row * row_samples;
        return std::any_of(marks, marks + row_samples, [](std::uint8_t mark) { return mark != 0; });
    };
    std::vector<OutlierCounts> per_group(static_cast<std::size_t>(groups));
    tbb::enumerable_thread_specific<GroupScratch> scratches;
    throw_if_cancelled();
    // One task cleans an image row's pieces in order, each reading the one
    // before as it was read; image rows (or runs of lone rows) run in parallel.
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, groups / pieces_per_row, 1),
                      [&](const tbb::blocked_range<std::int64_t>& range) {
                          GroupScratch& scratch = scratches.local();
                          for (std::int64_t task = range.begin(); task != range.end(); ++task) {
                              scratch.previous_rows = 0;
                              scratch.scale.clear();
                              if (scaled && row_is_cleaned(task))
                                  image_row_frame_scales(band, task * row_samples, layout, scratch);
                              for (std::int64_t g = task * pieces_per_row; g < (task + 1) * pieces_per_row; ++g) {
                                  std::int64_t first = 0;
                                  const GroupShape shape = shape_of(g, first);
                                  per_group[static_cast<std::size_t>(g)] =
                                      clean_group(band, first, shape, options, only, changed_rows, scratch);
                              }
                          }
                      });
    OutlierCounts total;
    for (const OutlierCounts& counts : per_group) {
        total.non_finite += counts.non_finite;
        total.fireflies += counts.fireflies;
    }
    return total;
}

} // namespace

OutlierCounts clean_outliers(MutableBandView band, const OutlierOptions& options, std::uint8_t* changed_rows,
                             const ImageRowLayout& layout)
{
    return clean_groups(band, options, layout, nullptr, changed_rows);
}

void clean_marked_outliers(MutableBandView band, const OutlierOptions& options,
                           const std::uint8_t* changed_rows, const ImageRowLayout& layout)
{
    clean_groups(band, options, layout, changed_rows, nullptr);
}

} // namespace modestack::lowrank
