// Confidence maps: sigma is calibrated on low-rank + Gaussian noise images, and
// stands out where the rebuild erases content present in a few frames only.
#include "core/lowrank/basis.h"
#include "core/lowrank/confidence.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/projection.h"
#include "core/lowrank/randomized_svd.h"
#include "tests/lowrank/synthetic.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>

using namespace modestack::lowrank;
using namespace modestack::lowrank::testing;

namespace {

constexpr int kWidth = 64;
constexpr int kHeight = 64;
constexpr int kChannels = 3;
constexpr int kFrames = 32;
constexpr int kRank = 2;
const ImageBandShape kShape{kWidth, kHeight, kChannels};

std::int64_t sample(int x, int y, int c)
{
    return (static_cast<std::int64_t>(y) * kWidth + x) * kChannels + c;
}

// Two smooth spatial modes with smooth temporal weights (rank 2), positive like light.
FrameMatrix clean_images()
{
    FrameMatrix clean(static_cast<std::int64_t>(kWidth) * kHeight * kChannels, kFrames);
    for (int t = 0; t < kFrames; ++t) {
        const double phase = 6.283185307179586 * t / kFrames;
        const double weight_one = 1.0 + 0.2 * std::sin(phase);
        const double weight_two = std::cos(1.5 * phase);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < kChannels; ++c) {
                    const double mode_one = 1.0 + 0.5 * std::sin(x / 10.0 + c) * std::cos(y / 13.0);
                    const double mode_two = 0.5 * std::cos(x / 7.0 + c) * std::sin(y / 9.0);
                    clean.at(sample(x, y, c), t) =
                        static_cast<float>(mode_one * weight_one + mode_two * weight_two);
                }
    }
    return clean;
}

// Noise whose standard deviation grows from left to right (renders are noisier in
// some places than others; sigma must follow).
FrameMatrix add_noise(const FrameMatrix& clean, std::uint64_t seed)
{
    FrameMatrix noisy = clean;
    const Eigen::MatrixXd noise = gaussian_matrix(static_cast<int>(clean.rows), kFrames, seed);
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < kChannels; ++c) {
                    const double deviation = 0.02 + 0.15 * x / (kWidth - 1.0);
                    noisy.at(sample(x, y, c), t) += static_cast<float>(deviation * noise(sample(x, y, c), t));
                }
    return noisy;
}

struct Rebuild {
    FrameMatrix rebuilt;
    Eigen::VectorXd leverage;
};

Rebuild rebuild(const FrameMatrix& noisy)
{
    GramAccumulator accumulator(kFrames);
    accumulator.add(noisy.view());
    const Basis basis = basis_from_gram(accumulator);
    Rebuild result{FrameMatrix(noisy.rows, kFrames), leverages(basis, kRank)};
    project_band(noisy.view(), basis.temporal.leftCols(kRank), result.rebuilt.mutable_view());
    return result;
}

FrameMatrix sigma_of(const FrameMatrix& noisy, const Rebuild& result, const ConfidenceOptions& options)
{
    FrameMatrix sigma(noisy.rows, kFrames);
    confidence_band(noisy.view(), result.rebuilt.view(), kShape, result.leverage, kRank, 0, kHeight, options,
                    sigma.mutable_view());
    return sigma;
}

double calibration_rms(const FrameMatrix& clean, const Rebuild& result, const FrameMatrix& sigma)
{
    double sum = 0;
    for (std::size_t k = 0; k < clean.data.size(); ++k) {
        const double z = (double(result.rebuilt.data[k]) - clean.data[k]) / sigma.data[k];
        sum += z * z;
    }
    return std::sqrt(sum / clean.data.size());
}

// Fraction of the top `fraction` of `error` (by index set) that is also in the top of `sigma`.
double top_overlap(const std::vector<double>& error, const std::vector<double>& sigma, double fraction)
{
    const std::size_t count = static_cast<std::size_t>(fraction * error.size());
    auto top = [&](const std::vector<double>& values) {
        std::vector<std::size_t> order(values.size());
        for (std::size_t k = 0; k < order.size(); ++k)
            order[k] = k;
        std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count), order.end(),
                          [&](std::size_t a, std::size_t b) { return values[a] > values[b]; });
        std::vector<char> in_top(values.size(), 0);
        for (std::size_t k = 0; k < count; ++k)
            in_top[order[k]] = 1;
        return in_top;
    };
    const std::vector<char> top_error = top(error), top_sigma = top(sigma);
    std::size_t both = 0;
    for (std::size_t k = 0; k < error.size(); ++k)
        both += top_error[k] && top_sigma[k];
    return double(both) / count;
}

} // namespace

TEST_CASE("sigma is calibrated on low-rank + Gaussian noise images")
{
    const FrameMatrix clean = clean_images();
    const FrameMatrix noisy = add_noise(clean, 5);
    const Rebuild result = rebuild(noisy);
    const double rms = calibration_rms(clean, result, sigma_of(noisy, result, ConfidenceOptions{}));
    ConfidenceOptions plain;
    plain.bias_significance = 0;
    const double rms_plain = calibration_rms(clean, result, sigma_of(noisy, result, plain));
    MESSAGE("RMS of (rebuilt - clean) / sigma: " << rms << " (plain bias formula z = 0: " << rms_plain
                                                 << ")");
    CHECK(rms >= 0.8);
    CHECK(rms <= 1.25);
}

TEST_CASE("sigma marks an object that the rebuild erases")
{
    const FrameMatrix base = clean_images();
    FrameMatrix clean = base;
    const std::vector<int> object_frames = {10, 11, 12};
    // 16×16 pixels (6 % of the image): an object and its shadow passing through.
    auto in_object = [](int x, int y) { return x >= 20 && x < 36 && y >= 24 && y < 40; };
    for (int t : object_frames)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                if (in_object(x, y))
                    for (int c = 0; c < kChannels; ++c)
                        clean.at(sample(x, y, c), t) += 1.5f;
    const FrameMatrix noisy = add_noise(clean, 6);
    const Rebuild result = rebuild(noisy);
    const FrameMatrix sigma = sigma_of(noisy, result, ConfidenceOptions{});

    double inside = 0, outside = 0;
    int inside_count = 0, outside_count = 0;
    for (int t : object_frames)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < kChannels; ++c) {
                    const double value = sigma.at(sample(x, y, c), t);
                    if (in_object(x, y)) {
                        inside += value;
                        ++inside_count;
                    } else {
                        outside += value;
                        ++outside_count;
                    }
                }
    const double ratio = (inside / inside_count) / (outside / outside_count);
    MESSAGE("mean sigma on the erased object / elsewhere in its frames: " << ratio);
    CHECK(ratio >= 5.0);

    // Every sample, and the samples of the object's frames only.
    std::vector<double> error, sigma_values, error_in_frames, sigma_in_frames;
    for (int t = 0; t < kFrames; ++t) {
        const bool object_frame =
            std::find(object_frames.begin(), object_frames.end(), t) != object_frames.end();
        for (std::int64_t i = 0; i < clean.rows; ++i) {
            error.push_back(std::abs(double(result.rebuilt.at(i, t)) - clean.at(i, t)));
            sigma_values.push_back(sigma.at(i, t));
            if (object_frame) {
                error_in_frames.push_back(error.back());
                sigma_in_frames.push_back(sigma_values.back());
            }
        }
    }
    const double overlap = top_overlap(error, sigma_values, 0.10);
    const double overlap_in_frames = top_overlap(error_in_frames, sigma_in_frames, 0.10);
    MESSAGE("top-10% true errors found among the top-10% sigma: " << 100 * overlap << " % of all samples, "
                                                                  << 100 * overlap_in_frames
                                                                  << " % in the object's frames");
    CHECK(overlap >= 0.60);
    CHECK(overlap_in_frames >= 0.60);

    // Every erased object sample ranks among the top 10 % sigma of its frame set.
    std::vector<double> sorted = sigma_in_frames;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(0.9 * sorted.size()),
                     sorted.end());
    const double top_decile = sorted[static_cast<std::size_t>(0.9 * sorted.size())];
    int flagged = 0, object_samples = 0;
    for (int t : object_frames)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                if (in_object(x, y))
                    for (int c = 0; c < kChannels; ++c) {
                        ++object_samples;
                        flagged += sigma.at(sample(x, y, c), t) >= top_decile;
                    }
    MESSAGE("object samples among the top-10% sigma: " << 100.0 * flagged / object_samples << " %");
    CHECK(flagged >= 0.95 * object_samples);
}

TEST_CASE("sigma of a band with halo rows equals the whole-image sigma, for 1 and 2 threads")
{
    const FrameMatrix noisy = add_noise(clean_images(), 7);
    const Rebuild result = rebuild(noisy);
    const FrameMatrix whole = sigma_of(noisy, result, ConfidenceOptions{});

    // Band of image rows [14, 40) with radius + 1 = 3 halo rows each side (the
    // high-pass reads one row beyond the window): valid rows [3, 23) of the band.
    const int first_row = 14, band_height = 26, radius = 3;
    const std::int64_t row_length = kWidth * kChannels;
    const std::int64_t offset = first_row * row_length;
    const BandView noisy_band{noisy.data.data() + offset, band_height * row_length, kFrames, noisy.rows};
    const BandView rebuilt_band{result.rebuilt.data.data() + offset, band_height * row_length, kFrames,
                                result.rebuilt.rows};
    const int valid_rows = band_height - 2 * radius;
    auto run = [&](int threads) {
        FrameMatrix band_sigma(valid_rows * row_length, kFrames);
        tbb::task_arena arena(threads);
        arena.execute([&] {
            confidence_band(noisy_band, rebuilt_band, ImageBandShape{kWidth, band_height, kChannels},
                            result.leverage, kRank, radius, band_height - radius, ConfidenceOptions{},
                            band_sigma.mutable_view());
        });
        return band_sigma;
    };
    const FrameMatrix one = run(1), two = run(2);
    CHECK(std::memcmp(one.data.data(), two.data.data(), sizeof(float) * one.data.size()) == 0);
    int mismatches = 0;
    for (int t = 0; t < kFrames; ++t)
        for (std::int64_t i = 0; i < one.rows; ++i)
            mismatches += one.at(i, t) != whole.at((first_row + radius) * row_length + i, t);
    CHECK(mismatches == 0);
}

TEST_CASE("sigma of an output that keeps a hundredth of the noise is not the bias term's noise")
{
    // A wide mode filter keeps a small share k of the noise (kept_noise = k); the
    // model is exact (rank 2), so the output's error is that noise alone. The
    // old bias term max(0, μ² − τ²) added about 0.48·τ² ≈ 0.02·s² everywhere,
    // twenty times the kept noise; the prior learnt per row shrinks it away.
    const FrameMatrix clean = clean_images();
    const FrameMatrix noisy = add_noise(clean, 9);
    const Rebuild result = rebuild(noisy);
    constexpr double kKept = 0.002;
    FrameMatrix kept(noisy.rows, kFrames);
    std::fill(kept.data.begin(), kept.data.end(), static_cast<float>(kKept));
    FrameMatrix sigma(noisy.rows, kFrames);
    const BandView kept_view = kept.view();
    confidence_band(noisy.view(), result.rebuilt.view(), kShape, result.leverage, kRank, 0, kHeight,
                    ConfidenceOptions{}, sigma.mutable_view(), &kept_view);
    // The filtered output: the truth plus √k of each sample's noise.
    const Eigen::MatrixXd noise = gaussian_matrix(static_cast<int>(clean.rows), kFrames, 21);
    double error = 0, variance = 0;
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < kChannels; ++c) {
                    const std::int64_t k = sample(x, y, c);
                    const double deviation = 0.02 + 0.15 * x / (kWidth - 1.0);
                    const double e = std::sqrt(kKept) * deviation * noise(k, t);
                    error += e * e;
                    variance += double(sigma.at(k, t)) * sigma.at(k, t);
                }
    const double ratio = std::sqrt(error / variance);
    MESSAGE("RMS(error) / RMS(sigma): " << ratio);
    CHECK(ratio >= 0.8);
    CHECK(ratio <= 1.25);
}
