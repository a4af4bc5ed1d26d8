#include "core/denoise/repeating_noise.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

namespace modestack::denoise {
namespace {

constexpr int kCoarse = 2; // the coarse term's distance along the row

// The middle frame of each triple of consecutive frames, spread over the shot
// with the first and last triple at its ends.
std::vector<int> triple_middles(int frames)
{
    const int triples = std::min(kRepeatingNoiseTriples, frames - 2);
    std::vector<int> middles;
    for (int k = 0; k < triples; ++k) {
        const int middle =
            1 + (triples == 1
                     ? 0
                     : static_cast<int>(std::lround(static_cast<double>(k) * (frames - 3) / (triples - 1))));
        if (middles.empty() || middle > middles.back())
            middles.push_back(middle);
    }
    return middles;
}

// (y(x − d) − 2·y(x) + y(x + d))² / 6 along the row: the same form as the
// term in time, so that both have the same distribution under noise that is
// new in every pixel and frame, whatever its shape. NaN past the row's ends or
// where a value is not finite.
float row_power(const float* row, int width, int x, int distance)
{
    if (x - distance < 0 || x + distance >= width)
        return std::numeric_limits<float>::quiet_NaN();
    const double d = static_cast<double>(row[x - distance]) - 2.0 * row[x] + row[x + distance];
    return static_cast<float>(d * d / 6);
}

// The median of the finite values among `values` (NaN when there is none): the
// upper middle one of an even count, so that it is one of the values.
float finite_median(float* values, int count)
{
    const int finite = static_cast<int>(
        std::partition(values, values + count, [](float v) { return std::isfinite(v); }) - values);
    if (finite == 0)
        return std::numeric_limits<float>::quiet_NaN();
    std::nth_element(values, values + finite / 2, values + finite);
    return values[finite / 2];
}

double median_of(std::vector<float>& values)
{
    const float median = finite_median(values.data(), static_cast<int>(values.size()));
    return std::isfinite(median) ? median : 0.0;
}

} // namespace

bool RepeatingNoise::counted() const
{
    return repeats && whiteness >= kCountedWhiteness;
}

std::vector<RepeatingNoise>
measure_repeating_noise(FrameSource& source, const std::vector<ChannelGroup>& groups, Progress& progress)
{
    const auto start = std::chrono::steady_clock::now();
    std::vector<RepeatingNoise> results(groups.size());
    const ShotShape shape = source.shape();
    if (shape.frames < 2 || shape.width <= 0 || shape.height <= 0 || shape.channels <= 0 || groups.empty())
        return results;
    const std::vector<int> middles = triple_middles(shape.frames);
    std::vector<int> frames;
    for (int middle : middles)
        for (int t : {middle - 1, middle, middle + 1})
            if (std::find(frames.begin(), frames.end(), t) == frames.end())
                frames.push_back(t);
    std::sort(frames.begin(), frames.end());
    // Per triple, the slots of its three frames among those read.
    std::vector<std::array<size_t, 3>> triples;
    for (int middle : middles) {
        std::array<size_t, 3> slots{};
        for (int j = 0; j < 3; ++j)
            slots[static_cast<size_t>(j)] =
                static_cast<size_t>(std::find(frames.begin(), frames.end(), middle - 1 + j) - frames.begin());
        triples.push_back(slots);
    }

    const int width = shape.width, channels = shape.channels, count = static_cast<int>(middles.size());
    const size_t pixels = static_cast<size_t>(width) * static_cast<size_t>(shape.height);
    // Per group, per pixel: the three medians over the triples.
    struct Powers {
        std::vector<float> temporal, spatial, coarse, magnitude;
    };
    std::vector<Powers> powers(groups.size(), {std::vector<float>(pixels), std::vector<float>(pixels),
                                               std::vector<float>(pixels), std::vector<float>(pixels)});
    // Per frame read: its rows as read, then per group the channel mean of each pixel.
    std::vector<std::vector<float>> rows(frames.size());
    std::vector<std::vector<std::vector<float>>> means(groups.size(),
                                                       std::vector<std::vector<float>>(frames.size()));
    progress.begin("looking for noise that repeats from frame to frame", shape.height);
    for (int row = 0; row < shape.height; row += kRepeatingNoiseBandRows) {
        throw_if_cancelled();
        const int end = std::min(shape.height, row + kRepeatingNoiseBandRows);
        const std::int64_t band_pixels = static_cast<std::int64_t>(width) * (end - row);
        tbb::parallel_for(size_t{0}, frames.size(), [&](size_t f) {
            rows[f].resize(static_cast<size_t>(band_pixels * channels));
            source.read_rows(frames[f], row, end, rows[f].data(), nullptr);
            for (size_t g = 0; g < groups.size(); ++g) {
                std::vector<float>& mean = means[g][f];
                mean.resize(static_cast<size_t>(band_pixels));
                for (std::int64_t p = 0; p < band_pixels; ++p) {
                    double sum = 0;
                    for (int c = groups[g].first; c < groups[g].first + groups[g].count; ++c)
                        sum += rows[f][static_cast<size_t>(p * channels + c)];
                    mean[static_cast<size_t>(p)] = static_cast<float>(sum / groups[g].count);
                }
            }
        });
        tbb::parallel_for(row, end, [&](int y) {
            std::array<float, kRepeatingNoiseTriples> time_terms{}, fine_terms{}, coarse_terms{},
                magnitudes{};
            for (size_t g = 0; g < groups.size(); ++g)
                for (int x = 0; x < width; ++x) {
                    const size_t here = static_cast<size_t>(static_cast<std::int64_t>(y - row) * width + x);
                    for (int k = 0; k < count; ++k) {
                        const std::array<size_t, 3>& slots = triples[static_cast<size_t>(k)];
                        const std::vector<float>& before = means[g][slots[0]];
                        const std::vector<float>& centre = means[g][slots[1]];
                        const std::vector<float>& after = means[g][slots[2]];
                        const double d = static_cast<double>(before[here]) - 2.0 * centre[here] + after[here];
                        time_terms[static_cast<size_t>(k)] = static_cast<float>(d * d / 6); // NaN stays NaN
                        const float* row_values = centre.data() + (here - static_cast<size_t>(x));
                        fine_terms[static_cast<size_t>(k)] = row_power(row_values, width, x, 1);
                        coarse_terms[static_cast<size_t>(k)] = row_power(row_values, width, x, kCoarse);
                        magnitudes[static_cast<size_t>(k)] = std::abs(centre[here]);
                    }
                    const size_t pixel =
                        static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
                    powers[g].temporal[pixel] = finite_median(time_terms.data(), count);
                    powers[g].spatial[pixel] = finite_median(fine_terms.data(), count);
                    powers[g].coarse[pixel] = finite_median(coarse_terms.data(), count);
                    powers[g].magnitude[pixel] = finite_median(magnitudes.data(), count);
                }
        });
        progress.advance(end - row);
    }
    progress.end();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (size_t g = 0; g < groups.size(); ++g) {
        RepeatingNoise& result = results[g];
        result.measured = true;
        result.seconds = seconds;
        result.frames = frames;
        result.temporal = median_of(powers[g].temporal);
        result.spatial = median_of(powers[g].spatial);
        result.coarse = median_of(powers[g].coarse);
        result.share =
            result.spatial > 0 ? std::clamp(1.0 - result.temporal / result.spatial, 0.0, 1.0) : 0.0;
        result.whiteness = result.coarse > 0 ? result.spatial / result.coarse : 0.0;
        const double magnitude = median_of(powers[g].magnitude);
        result.level = magnitude > 0 ? std::sqrt(result.spatial) / magnitude : 0.0;
        result.repeats = result.share >= 0.5 && result.whiteness >= 0.5 && result.level >= kLeastNoiseLevel;
    }
    return results;
}

RepeatingNoise measure_repeating_noise(FrameSource& source, Progress& progress)
{
    return measure_repeating_noise(source, {ChannelGroup{0, source.shape().channels}}, progress).front();
}

} // namespace modestack::denoise
