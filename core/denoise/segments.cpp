#include "core/denoise/segments.h"

#include "core/common/error.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace modestack::denoise {
namespace {

int parse_number(const std::string& text, const std::string& list)
{
    try {
        size_t used = 0;
        int value = std::stoi(text, &used);
        if (used == text.size())
            return value;
    } catch (const std::exception&) {
    }
    throw usage_error(
        fmt::format("--segments '{}': '{}' is not a frame number (write 1-30,31-60)", list, text));
}

double median_of(std::vector<double> values)
{
    if (values.empty())
        return 0;
    const size_t middle = values.size() / 2;
    std::nth_element(values.begin(), values.begin() + middle, values.end());
    double upper = values[middle];
    if (values.size() % 2 == 1)
        return upper;
    return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + middle));
}

// Block means of one frame: ceil(width / block) × ceil(height / block) × channels.
std::vector<double> block_means(FrameSource& source, int frame, int block)
{
    const ShotShape shape = source.shape();
    const int columns = (shape.width + block - 1) / block, rows = (shape.height + block - 1) / block;
    std::vector<double> sums(static_cast<size_t>(columns) * rows * shape.channels, 0.0);
    std::vector<double> counts(sums.size(), 0.0);
    std::vector<float> band(static_cast<size_t>(shape.width) * block * shape.channels);
    for (int y0 = 0; y0 < shape.height; y0 += block) {
        const int y1 = std::min(shape.height, y0 + block);
        source.read_rows(frame, y0, y1, band.data(), nullptr);
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < shape.width; ++x)
                for (int c = 0; c < shape.channels; ++c) {
                    const float value =
                        band[(static_cast<size_t>(y - y0) * shape.width + x) * shape.channels + c];
                    if (!std::isfinite(value))
                        continue;
                    const size_t cell =
                        (static_cast<size_t>(y0 / block) * columns + x / block) * shape.channels + c;
                    sums[cell] += value;
                    counts[cell] += 1;
                }
    }
    for (size_t i = 0; i < sums.size(); ++i)
        sums[i] = counts[i] > 0 ? sums[i] / counts[i] : 0.0;
    return sums;
}

} // namespace

std::vector<FrameSegment> parse_segments(const std::string& list, const std::vector<int>& frame_numbers)
{
    std::vector<FrameSegment> segments;
    size_t start = 0, next_index = 0;
    while (start <= list.size()) {
        const size_t comma = std::min(list.find(',', start), list.size());
        const std::string part = list.substr(start, comma - start);
        const size_t dash = part.find('-', 1); // a leading '-' is a negative frame number
        const int first = parse_number(part.substr(0, dash), list);
        const int last = dash == std::string::npos ? first : parse_number(part.substr(dash + 1), list);
        if (next_index >= frame_numbers.size())
            throw usage_error(fmt::format("--segments '{}': {} is past the shot's last frame {}", list, part,
                                          frame_numbers.back()));
        if (frame_numbers[next_index] != first)
            throw usage_error(
                fmt::format("--segments '{}': part {} should start at frame {} (the parts must cover "
                            "every frame in order, without gaps or overlaps)",
                            list, part, frame_numbers[next_index]));
        auto end = std::find(frame_numbers.begin() + static_cast<std::ptrdiff_t>(next_index),
                             frame_numbers.end(), last);
        if (end == frame_numbers.end())
            throw usage_error(fmt::format("--segments '{}': frame {} is not in the shot", list, last));
        const int count = static_cast<int>(end - frame_numbers.begin()) - static_cast<int>(next_index) + 1;
        if (count < 3)
            throw usage_error(fmt::format(
                "--segments '{}': part {} has {} frames, the denoiser needs at least 3", list, part, count));
        segments.push_back({static_cast<int>(next_index), count});
        next_index += static_cast<size_t>(count);
        start = comma + 1;
    }
    if (next_index != frame_numbers.size())
        throw usage_error(fmt::format("--segments '{}': frames {} to {} are in no part", list,
                                      frame_numbers[next_index], frame_numbers.back()));
    return segments;
}

CutSearch find_cuts(FrameSource& source, const CutSearchOptions& options)
{
    const ShotShape shape = source.shape();
    CutSearch search;
    if (shape.frames < 2)
        return search;
    std::vector<std::vector<double>> means(static_cast<size_t>(shape.frames));
    tbb::parallel_for(0, shape.frames,
                      [&](int t) { means[static_cast<size_t>(t)] = block_means(source, t, options.block); });
    throw_if_cancelled();
    for (int t = 1; t < shape.frames; ++t) {
        const std::vector<double>&a = means[static_cast<size_t>(t - 1)], &b = means[static_cast<size_t>(t)];
        double sum = 0;
        for (size_t i = 0; i < a.size(); ++i)
            sum += (b[i] - a[i]) * (b[i] - a[i]);
        search.distances.push_back(std::sqrt(sum / static_cast<double>(a.size())));
    }
    search.median = median_of(search.distances);
    std::vector<double> deviations;
    for (double d : search.distances)
        deviations.push_back(std::fabs(d - search.median));
    search.threshold = std::max(search.median + options.mad_factor * 1.4826 * median_of(deviations),
                                options.median_ratio * search.median);
    // Strongest jumps first; a cut is kept when it leaves every part long enough.
    std::vector<int> order(search.distances.size());
    std::iota(order.begin(), order.end(), 1);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return search.distances[a - 1] > search.distances[b - 1]; });
    for (int t : order) {
        if (!(search.distances[static_cast<size_t>(t - 1)] > search.threshold))
            break;
        std::vector<int> cuts = search.cuts;
        cuts.insert(std::upper_bound(cuts.begin(), cuts.end(), t), t);
        bool long_enough = true;
        for (const FrameSegment& segment : segments_from_cuts(cuts, shape.frames))
            long_enough = long_enough && segment.count >= options.min_segment_frames;
        if (long_enough)
            search.cuts = cuts;
    }
    return search;
}

std::vector<FrameSegment> segments_from_cuts(const std::vector<int>& cuts, int frames)
{
    std::vector<FrameSegment> segments;
    int first = 0;
    for (int cut : cuts) {
        segments.push_back({first, cut - first});
        first = cut;
    }
    segments.push_back({first, frames - first});
    return segments;
}

ShotShape FrameRangeSource::shape() const
{
    ShotShape shape = m_inner.shape();
    shape.frames = m_segment.count;
    return shape;
}

std::int64_t FrameRangeSource::band_bytes_per_row() const
{
    return m_inner.band_bytes_per_row(); // all frames': an upper bound for the plan
}

std::vector<Report> run_segments(FrameSource& source, FrameSink& sink, const Settings& settings,
                                 const std::vector<FrameSegment>& segments, Progress& progress)
{
    if (segments.size() > 1 && sink.wants_modes())
        throw usage_error(
            "--segments with several parts cannot save spatial modes (--save-modes): each part has "
            "modes of its own");
    std::vector<Report> reports;
    for (size_t k = 0; k < segments.size(); ++k) {
        FrameRangeSource part(source, segments[k]);
        FrameRangeSink part_sink(sink, segments[k], k == 0);
        reports.push_back(run_denoise(part, part_sink, settings, progress));
    }
    return reports;
}

Report merge_reports(const std::vector<Report>& reports)
{
    Report merged = reports.at(0);
    merged.temporal_modes.clear();
    merged.rebuild_weights.clear();
    for (size_t k = 1; k < reports.size(); ++k) {
        const Report& part = reports[k];
        merged.shape.frames += part.shape.frames;
        merged.passes += part.passes;
        merged.outliers.non_finite += part.outliers.non_finite;
        merged.outliers.fireflies += part.outliers.fireflies;
        merged.non_negative += part.non_negative;
        merged.estimator_choice.insert(merged.estimator_choice.end(), part.estimator_choice.begin(),
                                       part.estimator_choice.end());
        merged.frame_noise_factors.insert(merged.frame_noise_factors.end(), part.frame_noise_factors.begin(),
                                          part.frame_noise_factors.end()); // each over its own segment
        if (part.repeating_noise.repeats && !merged.repeating_noise.repeats)
            merged.repeating_noise = part.repeating_noise; // said of the shot when any part has it
        merged.seconds_filter_survey += part.seconds_filter_survey;
        merged.seconds_statistics += part.seconds_statistics;
        merged.seconds_solve += part.seconds_solve;
        merged.seconds_rebuild += part.seconds_rebuild;
    }
    // Each part's frame scales over its own frames; a part fitted to even noise
    // (the randomized SVD) counts 1 in each of its frames. None anywhere: even.
    merged.frame_scales.clear();
    const bool measured = std::any_of(reports.begin(), reports.end(),
                                      [](const Report& part) { return !part.frame_scales.empty(); });
    for (size_t k = 0; measured && k < reports.size(); ++k) {
        const Report& part = reports[k];
        if (part.frame_scales.empty())
            merged.frame_scales.insert(merged.frame_scales.end(), static_cast<size_t>(part.shape.frames),
                                       1.0);
        else
            merged.frame_scales.insert(merged.frame_scales.end(), part.frame_scales.begin(),
                                       part.frame_scales.end());
    }
    return merged;
}

} // namespace modestack::denoise
