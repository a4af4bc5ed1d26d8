// Outlier cleaning: NaN/Inf replaced by the row median and counted, fireflies
// clamped with the row's temporal sum preserved, clean data left bit-exact, and the
// same result with 1 and 2 threads, re-cleaning only the marked rows of a fresh
// read gives the same bits as cleaning it all, and the clamp's shortcuts give the
// bits of the plain rule; light that row neighbours share in a frame is not
// taken for fireflies.
#include "core/common/error.h"
#include "core/lowrank/outliers.h"
#include "tests/lowrank/synthetic.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace modestack::lowrank;
using namespace modestack::lowrank::testing;

namespace {

FrameMatrix positive_noisy(std::int64_t rows, int frames, std::uint64_t seed)
{
    FrameMatrix matrix = low_rank_matrix(rows, frames, {1.0, 0.3}, seed);
    add_gaussian_noise(matrix, 0.1, seed + 1);
    for (float& value : matrix.data)
        value = std::abs(value) + 1.0f; // radiance-like: positive
    return matrix;
}

double row_sum(const FrameMatrix& matrix, std::int64_t row)
{
    double sum = 0;
    for (int t = 0; t < matrix.frames; ++t)
        sum += matrix.at(row, t);
    return sum;
}

} // namespace

TEST_CASE("NaN and Inf are replaced by the row's median of finite values and counted")
{
    FrameMatrix matrix = positive_noisy(3000, 9, 1);
    const FrameMatrix original = matrix;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    matrix.at(10, 2) = nan;
    matrix.at(10, 5) = inf;
    matrix.at(2500, 0) = -inf;
    for (int t = 0; t < 9; ++t)
        matrix.at(77, t) = nan; // nothing finite: becomes 0

    // Expected: the median of the 7 finite values of row 10 (odd count: the middle one).
    std::vector<float> finite;
    for (int t = 0; t < 9; ++t)
        if (t != 2 && t != 5)
            finite.push_back(matrix.at(10, t));
    std::sort(finite.begin(), finite.end());
    std::vector<float> finite_2500;
    for (int t = 1; t < 9; ++t)
        finite_2500.push_back(matrix.at(2500, t));
    std::sort(finite_2500.begin(), finite_2500.end());

    OutlierOptions options;
    options.fireflies = false;
    const OutlierCounts counts = clean_outliers(matrix.mutable_view(), options);
    CHECK(counts.non_finite == 12);
    CHECK(counts.fireflies == 0);
    CHECK(matrix.at(10, 2) == finite[3]);
    CHECK(matrix.at(10, 5) == finite[3]);
    CHECK(matrix.at(2500, 0) == doctest::Approx(0.5 * (finite_2500[3] + finite_2500[4])));
    for (int t = 0; t < 9; ++t)
        CHECK(matrix.at(77, t) == 0.0f);
    for (float value : matrix.data)
        CHECK_FALSE(!std::isfinite(value));
    CHECK(matrix.at(11, 3) == original.at(11, 3));
}

TEST_CASE("a huge spike is clamped and its energy stays in the row")
{
    FrameMatrix matrix = positive_noisy(3000, 24, 11);
    const FrameMatrix original = matrix;
    matrix.at(1234, 6) = 5000.0f;
    const double sum_before = row_sum(matrix, 1234);
    const OutlierCounts counts = clean_outliers(matrix.mutable_view());
    CHECK(counts.fireflies == 1);
    CHECK(counts.non_finite == 0);
    const double sum_after = row_sum(matrix, 1234);
    MESSAGE("row sum before " << sum_before << ", after " << sum_after);
    CHECK(std::abs(sum_after - sum_before) <= 1e-5 * std::abs(sum_before));
    // Clamped: the spike is gone, its excess spread evenly over the other frames.
    const float share = matrix.at(1234, 0) - original.at(1234, 0);
    // The clamp level is median + 6·1.4826·max(MAD, 0.1·median |x|) of the row with its
    // spike (here the floor decides: the row's MAD is about 3 % of its level).
    std::vector<double> values;
    for (int t = 0; t < 24; ++t)
        values.push_back(t == 6 ? 5000.0 : original.at(1234, t));
    std::sort(values.begin(), values.end());
    const double median = 0.5 * (values[11] + values[12]);
    for (double& value : values)
        value = std::abs(value - median);
    std::sort(values.begin(), values.end());
    const double mad = 0.5 * (values[11] + values[12]);
    const double threshold = median + 6 * 1.4826 * std::max(mad, 0.1 * median);
    CHECK(matrix.at(1234, 6) - share == doctest::Approx(threshold).epsilon(1e-4));
    // 24·share = 5000 − threshold and the spike ends at threshold + share.
    CHECK(share == doctest::Approx((5000.0 - matrix.at(1234, 6)) / 23).epsilon(1e-3));
    for (int t = 0; t < 24; ++t)
        if (t != 6)
            CHECK(matrix.at(1234, t) - original.at(1234, t) == doctest::Approx(share).epsilon(1e-3));
    // Every other row is untouched.
    for (std::int64_t i = 0; i < matrix.rows; ++i)
        if (i != 1234)
            for (int t = 0; t < 24; ++t)
                REQUIRE(matrix.at(i, t) == original.at(i, t));
}

TEST_CASE("clean data is left bit-exact")
{
    FrameMatrix matrix = positive_noisy(5000, 24, 21);
    const FrameMatrix original = matrix;
    const OutlierCounts counts = clean_outliers(matrix.mutable_view());
    CHECK(counts.non_finite == 0);
    CHECK(counts.fireflies == 0);
    CHECK(std::memcmp(matrix.data.data(), original.data.data(), sizeof(float) * matrix.data.size()) == 0);
}

TEST_CASE("outlier cleaning is bit-identical with 1 and 2 threads, with and without row neighbours")
{
    for (const ImageRowLayout layout : {ImageRowLayout{}, ImageRowLayout{50, 4}}) {
        FrameMatrix input = positive_noisy(20000, 16, 31);
        for (std::int64_t i = 0; i < input.rows; i += 97)
            input.at(i, static_cast<int>(i % 16)) =
                (i % 3 == 0) ? std::numeric_limits<float>::quiet_NaN() : 300.0f;
        auto run = [&](int threads, FrameMatrix& matrix, OutlierCounts& counts) {
            tbb::task_arena arena(threads);
            arena.execute([&] { counts = clean_outliers(matrix.mutable_view(), {}, nullptr, layout); });
        };
        FrameMatrix one = input, two = input;
        OutlierCounts counts_one, counts_two;
        run(1, one, counts_one);
        run(2, two, counts_two);
        CHECK(counts_one.non_finite == counts_two.non_finite);
        CHECK(counts_one.fireflies == counts_two.fireflies);
        CHECK(counts_one.non_finite + counts_one.fireflies == (input.rows + 96) / 97);
        CHECK(std::memcmp(one.data.data(), two.data.data(), sizeof(float) * one.data.size()) == 0);
    }
}

TEST_CASE(
    "re-cleaning only the marked rows of a fresh read gives the same bits, with and without row neighbours")
{
    for (const ImageRowLayout layout : {ImageRowLayout{}, ImageRowLayout{50, 4}}) {
        FrameMatrix input = positive_noisy(20000, 16, 41);
        for (std::int64_t i = 0; i < input.rows; i += 89)
            input.at(i, static_cast<int>(i % 16)) =
                (i % 2 == 0) ? std::numeric_limits<float>::infinity() : 500.0f;
        FrameMatrix first = input, again = input;
        std::vector<std::uint8_t> marks(static_cast<std::size_t>(input.rows), 7);
        const OutlierCounts counts = clean_outliers(first.mutable_view(), {}, marks.data(), layout);
        const auto marked = std::count(marks.begin(), marks.end(), std::uint8_t(1));
        CHECK(std::count(marks.begin(), marks.end(), std::uint8_t(0)) + marked == input.rows);
        CHECK(marked == (input.rows + 88) / 89);
        CHECK(counts.non_finite + counts.fireflies >= marked);
        clean_marked_outliers(again.mutable_view(), {}, marks.data(), layout);
        CHECK(std::memcmp(first.data.data(), again.data.data(), sizeof(float) * first.data.size()) == 0);
    }
}

namespace {

// The firefly rule of outliers.h written out plainly (full sorts, every median
// computed), to check that clean_outliers' shortcuts change no bit.
double plain_median(std::vector<double> values)
{
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::int64_t plain_clamp(std::vector<double>& row, const OutlierOptions& options)
{
    const double median = plain_median(row);
    std::vector<double> deviations, magnitudes;
    for (double value : row) {
        deviations.push_back(std::abs(value - median));
        magnitudes.push_back(std::abs(value));
    }
    const double mad = plain_median(deviations);
    const double typical = *std::min_element(row.begin(), row.end()) >= 0 ? median : plain_median(magnitudes);
    const double threshold =
        median + options.firefly_k * 1.4826 * std::max({mad, options.mad_floor_fraction * typical, 1e-30});
    double excess = 0;
    std::int64_t clamped = 0;
    for (double& value : row)
        if (value > threshold)
            excess += value - threshold, value = threshold, ++clamped;
    if (excess > 0)
        for (double& value : row)
            value += excess / static_cast<double>(row.size());
    return clamped;
}

} // namespace

TEST_CASE("firefly clamping matches the plain rule bit for bit on heavy-tailed rows")
{
    // Rows of a render's kinds: smooth, noisy, heavy-tailed (most rows clean, some
    // with fireflies), signed, and exactly at the floor; odd and even frame counts.
    for (int frames : {7, 24, 101}) {
        const std::int64_t rows = 4000;
        FrameMatrix matrix(rows, frames);
        std::uint64_t state = 12345u + static_cast<std::uint64_t>(frames);
        auto uniform = [&] {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return static_cast<double>(state >> 11) * 0x1.0p-53;
        };
        for (std::int64_t i = 0; i < rows; ++i) {
            const int kind = static_cast<int>(i % 5);
            for (int t = 0; t < frames; ++t) {
                const double u = std::max(uniform(), 1e-12);
                double value = 1.0;
                if (kind == 1)
                    value = 0.5 + uniform();
                else if (kind == 2)
                    value = 0.2 / std::pow(u, 0.8); // Pareto-like: 4-spp fireflies
                else if (kind == 3)
                    value = uniform() - 0.5 + (u < 0.02 ? 40.0 : 0.0);
                else if (kind == 4)
                    value = (t % 3 == 0) ? 1.0 : 1.0 + 6 * 1.4826 * 0.1; // the floor's threshold itself
                matrix.at(i, t) = static_cast<float>(value);
            }
        }
        FrameMatrix expected = matrix;
        std::int64_t expected_fireflies = 0;
        for (std::int64_t i = 0; i < rows; ++i) {
            std::vector<double> row;
            for (int t = 0; t < frames; ++t)
                row.push_back(expected.at(i, t));
            expected_fireflies += plain_clamp(row, {});
            for (int t = 0; t < frames; ++t)
                expected.at(i, t) = static_cast<float>(row[static_cast<std::size_t>(t)]);
        }
        const OutlierCounts counts = clean_outliers(matrix.mutable_view());
        MESSAGE(frames << " frames: " << counts.fireflies << " fireflies");
        CHECK(counts.fireflies == expected_fireflies);
        CHECK(counts.fireflies > rows / 50);
        CHECK(std::memcmp(matrix.data.data(), expected.data.data(), sizeof(float) * matrix.data.size()) == 0);
    }
}

TEST_CASE("light the row neighbours share in a frame is kept, and a lone firefly beside it or on it is clamped")
{
    // One image row of 60 RGB pixels over 24 frames; pixels 20–39 lit 20× brighter
    // in frames 10–12 (a light passing), a firefly beside the light (pixel 5,
    // spread onto pixel 6 as a pixel filter would) and one on it (pixel 30, in a
    // lit frame).
    constexpr int kWidth = 60, kChannels = 3, kFrames = 24;
    FrameMatrix input = positive_noisy(kWidth * kChannels, kFrames, 51);
    for (int x = 20; x < 40; ++x)
        for (int c = 0; c < kChannels; ++c)
            for (int t = 10; t <= 12; ++t)
                input.at(x * kChannels + c, t) += 20.0f;
    const std::int64_t beside = 5 * kChannels + 0, on = 30 * kChannels + 1;
    const std::int64_t spread_onto = beside + kChannels; // as a pixel filter spreads it
    input.at(beside, 3) = 500.0f;
    input.at(spread_onto, 3) = 200.0f;
    input.at(on, 11) = 500.0f;

    FrameMatrix with_neighbours = input;
    const OutlierCounts counts =
        clean_outliers(with_neighbours.mutable_view(), {}, nullptr, ImageRowLayout{kWidth, kChannels});
    CHECK(counts.fireflies == 3);
    for (std::int64_t i = 0; i < input.rows; ++i) {
        if (i == beside || i == spread_onto || i == on) {
            CHECK(with_neighbours.at(i, i == on ? 11 : 3) < 100.0f);
            CHECK(row_sum(with_neighbours, i) == doctest::Approx(row_sum(input, i)).epsilon(1e-6));
            continue;
        }
        for (int t = 0; t < kFrames; ++t)
            REQUIRE(with_neighbours.at(i, t) == input.at(i, t)); // the lit frames, their edges too
    }

    // Each row on its own cannot tell the light from fireflies: it flattens the
    // light's three frames into all 24.
    FrameMatrix alone = input;
    const OutlierCounts alone_counts = clean_outliers(alone.mutable_view());
    MESSAGE("clamped without row neighbours: " << alone_counts.fireflies);
    CHECK(alone_counts.fireflies >= 20 * kChannels * 3);
    CHECK(alone.at(25 * kChannels, 11) < 0.5f * input.at(25 * kChannels, 11));
}

TEST_CASE("a band that is not whole image rows of its layout is an internal error")
{
    FrameMatrix matrix = positive_noisy(100, 8, 61);
    CHECK_THROWS_AS(clean_outliers(matrix.mutable_view(), {}, nullptr, ImageRowLayout{30, 3}),
                    modestack::Error);
}

namespace {

// Each frame's noise scale along every image row (OutlierOptions::
// per_frame_noise) written out plainly: the median |x − (left + right)/2| of
// the row's finite values as read (every step-th pixel's on a row of more than
// 2 × 1024 samples; the upper middle one, by a full sort), over
// the mean of the frames' medians, at least kLeastFrameScale; 1 where all are 0.
std::vector<std::vector<double>> plain_frame_scales(const FrameMatrix& matrix, int width, int channels)
{
    const int frames = matrix.frames;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    std::vector<std::vector<double>> scales;
    for (std::int64_t first = 0; first < matrix.rows; first += row_samples) {
        std::vector<double> scale(static_cast<std::size_t>(frames));
        double sum = 0;
        for (int t = 0; t < frames; ++t) {
            std::vector<float> high_pass;
            const std::int64_t step =
                std::max<std::int64_t>(1, row_samples / 1024); // outliers.cpp's kScaleSamples
            for (std::int64_t i = channels; i + channels < row_samples; ++i) {
                if ((i / channels - 1) % step != 0)
                    continue;
                const double d = static_cast<double>(matrix.at(first + i, t)) -
                                 0.5 * (static_cast<double>(matrix.at(first + i - channels, t)) +
                                        matrix.at(first + i + channels, t));
                if (std::isfinite(d))
                    high_pass.push_back(static_cast<float>(std::abs(d)));
            }
            std::sort(high_pass.begin(), high_pass.end());
            scale[static_cast<std::size_t>(t)] = high_pass.empty() ? 0.0 : high_pass[high_pass.size() / 2];
            sum += scale[static_cast<std::size_t>(t)];
        }
        for (double& value : scale)
            value = sum > 0 ? std::max(value / (sum / frames), kLeastFrameScale) : 1.0;
        scales.push_back(scale);
    }
    return scales;
}

// The rule with row neighbours written out plainly (outliers.h): every row's
// NaN/Inf replaced first, its median and plain threshold by full sorts, then
// each sample above the plain threshold judged against the lifted one; with
// per_frame_noise, each frame's thresholds at its own scale.
std::int64_t plain_clean_with_neighbours(FrameMatrix& matrix, int width, int channels,
                                         const OutlierOptions& options)
{
    const int frames = matrix.frames;
    const std::vector<std::vector<double>> scales = options.per_frame_noise
                                                        ? plain_frame_scales(matrix, width, channels)
                                                        : std::vector<std::vector<double>>{};
    std::vector<std::vector<double>> rows(static_cast<std::size_t>(matrix.rows));
    std::vector<double> medians(rows.size());
    for (std::int64_t i = 0; i < matrix.rows; ++i) {
        std::vector<double> finite;
        for (int t = 0; t < frames; ++t)
            if (std::isfinite(matrix.at(i, t)))
                finite.push_back(matrix.at(i, t));
        const double fill = finite.empty() ? 0.0 : plain_median(finite);
        for (int t = 0; t < frames; ++t)
            rows[static_cast<std::size_t>(i)].push_back(std::isfinite(matrix.at(i, t)) ? matrix.at(i, t) : fill);
        medians[static_cast<std::size_t>(i)] = plain_median(rows[static_cast<std::size_t>(i)]);
    }
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    std::int64_t clamped = 0;
    for (std::int64_t i = 0; i < matrix.rows; ++i) {
        std::vector<double> row = rows[static_cast<std::size_t>(i)];
        const double median = medians[static_cast<std::size_t>(i)];
        const auto scale = [&](int t) {
            return scales.empty()
                       ? 1.0
                       : scales[static_cast<std::size_t>(i / row_samples)][static_cast<std::size_t>(t)];
        };
        std::vector<double> deviations, magnitudes;
        for (int t = 0; t < frames; ++t) {
            const double value = row[static_cast<std::size_t>(t)];
            deviations.push_back(scales.empty() ? std::abs(value - median)
                                                : std::abs(value - median) / scale(t));
            magnitudes.push_back(std::abs(value));
        }
        const double typical = *std::min_element(row.begin(), row.end()) >= 0 ? median : plain_median(magnitudes);
        const double floor = std::max(options.mad_floor_fraction * typical, 1e-30),
                     mad = plain_median(deviations);
        const auto spread_of = [&](int t) {
            return scales.empty() ? std::max(mad, floor) : std::max(mad * scale(t), floor);
        };
        const std::int64_t x = (i % row_samples) / channels;
        const auto excess = [&](int dx, int t) {
            if (x + dx < 0 || x + dx >= width)
                return -std::numeric_limits<double>::infinity();
            const std::size_t q = static_cast<std::size_t>(i + dx * channels);
            return rows[q][static_cast<std::size_t>(t)] - medians[q];
        };
        double removed = 0;
        for (int t = 0; t < frames; ++t) {
            double& value = row[static_cast<std::size_t>(t)];
            const double spread = spread_of(t), plain = median + options.firefly_k * 1.4826 * spread;
            if (!(value > plain))
                continue;
            const double shared = std::max(
                {std::min(excess(-1, t), excess(-2, t)), std::min(excess(1, t), excess(2, t)), 0.0});
            double threshold = plain;
            if (shared > 0) {
                const double expected = median + shared;
                const double level = typical > 0 && expected > typical ? expected / typical : 1.0;
                threshold = expected + options.firefly_k * 1.4826 *
                                           std::max(spread * level, options.mad_floor_fraction * std::abs(expected));
            }
            CHECK(threshold >= plain);
            if (value > threshold)
                removed += value - threshold, value = threshold, ++clamped;
        }
        if (removed > 0)
            for (double& value : row)
                value += removed / static_cast<double>(frames);
        for (int t = 0; t < frames; ++t)
            matrix.at(i, t) = static_cast<float>(row[static_cast<std::size_t>(t)]);
    }
    return clamped;
}

// An image of `height` rows of `width` RGB pixels over `frames` frames with the
// kinds of light the rule must tell apart: heavy-tailed noise, signed values,
// pixels dark in most frames, noisy rows whose MAD is above the floor, patches
// of light that neighbours share in a few frames, fireflies, and NaN/Inf
// beside fireflies.
// `noisier`: the noise of the last third of the frames is that many times
// the rest's (a light switched on).
FrameMatrix mixed_image(int width, int height, int frames, std::uint64_t seed, double noisier = 1)
{
    constexpr int kChannels = 3;
    FrameMatrix matrix(static_cast<std::int64_t>(width) * height * kChannels, frames);
    std::uint64_t state = seed;
    auto uniform = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int kind = (x / 4 + y) % 5;
            for (int c = 0; c < kChannels; ++c)
                for (int t = 0; t < frames; ++t) {
                    const double u = std::max(uniform(), 1e-12);
                    double value = 0.2 / std::pow(u, 0.8); // heavy-tailed
                    if (kind == 1)
                        value = uniform() - 0.5 + (u < 0.02 ? 40.0 : 0.0); // signed
                    else if (kind == 2)
                        value = (t * 7 + x) % 10 < 6 ? 0.0 : 1.0 + 0.5 * uniform(); // dark in most frames
                    else if (kind == 3)
                        value = 1.0 + 2.0 * uniform(); // MAD above the floor
                    if (3 * t >= 2 * frames && (kind == 0 || kind == 3))
                        value *= noisier;
                    if ((x / 6 + t) % 9 == 0 && y % 3 != 0)
                        value += 15.0 + uniform(); // light its neighbours share
                    const std::int64_t i = (static_cast<std::int64_t>(y) * width + x) * kChannels + c;
                    matrix.at(i, t) = static_cast<float>(value);
                }
        }
    for (std::int64_t i = 5; i < matrix.rows; i += 37) {
        const int t = static_cast<int>(i % frames);
        matrix.at(i, t) = 900.0f;
        if (i + kChannels < matrix.rows)
            matrix.at(i + kChannels, t) = (i % 2 == 0) ? std::numeric_limits<float>::quiet_NaN()
                                                        : std::numeric_limits<float>::infinity();
    }
    return matrix;
}

} // namespace

TEST_CASE("row neighbours: the rule written out plainly gives the same bits")
{
    // 300 and 800 pixels: image rows are cleaned in pieces of 128 pixels, each with its
    // neighbours; 800 pixels are more than 1024 samples: the frame scales read every other pixel.
    for (const auto [frames, width, height] :
         {std::array{7, 40, 12}, std::array{24, 300, 4}, std::array{7, 800, 2}})
        for (const bool per_frame : {false, true}) {
            OutlierOptions options;
            options.per_frame_noise = per_frame;
            FrameMatrix matrix =
                mixed_image(width, height, frames, 99u + static_cast<std::uint64_t>(frames), 4.0);
            FrameMatrix expected = matrix;
            const std::int64_t expected_fireflies = plain_clean_with_neighbours(expected, width, 3, options);
            const OutlierCounts counts =
                clean_outliers(matrix.mutable_view(), options, nullptr, ImageRowLayout{width, 3});
            MESSAGE(frames << " frames, per-frame noise " << per_frame << ": " << counts.fireflies
                           << " fireflies, " << counts.non_finite << " NaN/Inf");
            CHECK(counts.fireflies == expected_fireflies);
            CHECK(counts.fireflies > 0);
            CHECK(counts.non_finite > 0);
            CHECK(std::memcmp(matrix.data.data(), expected.data.data(), sizeof(float) * matrix.data.size()) ==
                  0);
        }
}

TEST_CASE("row neighbours: bands of whole image rows, cut anywhere, give the bits of the whole image")
{
    const int width = 300, height = 12, frames = 24;
    const std::int64_t row_samples = width * 3;
    const FrameMatrix input = mixed_image(width, height, frames, 7, 4.0);
    FrameMatrix whole = input;
    clean_outliers(whole.mutable_view(), {}, nullptr, ImageRowLayout{width, 3});
    for (int band_height : {1, 5, 7}) {
        FrameMatrix banded = input, marked_again = input;
        for (int y = 0; y < height; y += band_height) {
            const std::int64_t first = y * row_samples;
            const std::int64_t rows = std::min(band_height, height - y) * row_samples;
            const MutableBandView band{&banded.at(first, 0), rows, frames, banded.rows};
            std::vector<std::uint8_t> marks(static_cast<std::size_t>(rows));
            clean_outliers(band, {}, marks.data(), ImageRowLayout{width, 3});
            const MutableBandView again{&marked_again.at(first, 0), rows, frames, marked_again.rows};
            clean_marked_outliers(again, {}, marks.data(), ImageRowLayout{width, 3});
        }
        CHECK(std::memcmp(banded.data.data(), whole.data.data(), sizeof(float) * whole.data.size()) == 0);
        CHECK(std::memcmp(marked_again.data.data(), whole.data.data(), sizeof(float) * whole.data.size()) == 0);
    }
}

TEST_CASE(
    "per-frame noise: frames 8x as noisy keep their own samples, and the clean frames are not brightened")
{
    // Image rows of 1 plus exponential noise (render noise is skewed): of scale
    // 0.1 in frames 0–15 and 0.8 in frames 16–23 (a large light switched on),
    // and one firefly. One threshold for all frames, set by the quiet majority,
    // takes the noisy frames' upper samples for fireflies and spreads their
    // excess over every frame: the quiet frames come out brighter.
    constexpr int kWidth = 200, kHeight = 4, kChannels = 3, kFrames = 24, kQuiet = 16;
    const std::int64_t rows = static_cast<std::int64_t>(kWidth) * kHeight * kChannels;
    FrameMatrix input(rows, kFrames);
    std::uint64_t state = 2024;
    auto uniform = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    for (std::int64_t i = 0; i < rows; ++i)
        for (int t = 0; t < kFrames; ++t)
            input.at(i, t) =
                static_cast<float>(1.0 - (t < kQuiet ? 0.1 : 0.8) * std::log(std::max(uniform(), 1e-12)));
    const std::int64_t firefly = 7 * kChannels + 1;
    input.at(firefly, 20) = 100.0f; // a real one, in a noisy frame
    const auto quiet_mean = [&](const FrameMatrix& matrix) {
        double sum = 0;
        for (std::int64_t i = 0; i < rows; ++i)
            for (int t = 0; t < kQuiet; ++t)
                sum += matrix.at(i, t);
        return sum / static_cast<double>(rows * kQuiet);
    };
    const double before = quiet_mean(input);

    FrameMatrix scaled = input, even = input;
    OutlierOptions per_frame, one_threshold;
    per_frame.per_frame_noise = true;
    one_threshold.per_frame_noise = false;
    const ImageRowLayout layout{kWidth, kChannels};
    const OutlierCounts scaled_counts = clean_outliers(scaled.mutable_view(), per_frame, nullptr, layout);
    const OutlierCounts even_counts = clean_outliers(even.mutable_view(), one_threshold, nullptr, layout);
    MESSAGE("clamped: per frame " << scaled_counts.fireflies << ", one threshold " << even_counts.fireflies
                                  << "; quiet frames' mean " << before << " -> " << quiet_mean(scaled)
                                  << " / " << quiet_mean(even));
    // Judged at its own scale, a frame's exponential tail passes the threshold
    // in about 0.1 % of the samples; one threshold clamps a tenth of the noisy
    // frames' samples.
    CHECK(scaled_counts.fireflies < rows * kFrames / 500);
    CHECK(scaled.at(firefly, 20) < 20.0f);
    CHECK(even_counts.fireflies > rows * (kFrames - kQuiet) / 10);
    CHECK(quiet_mean(scaled) < before * 1.005);
    CHECK(quiet_mean(even) > before * 1.02);
}
