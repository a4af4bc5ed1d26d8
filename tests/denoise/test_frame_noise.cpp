// Each frame's noise factor (core/denoise/frame_noise.h): the mean absolute
// horizontal high-pass of a frame over the shot's mean. It recovers the ratio
// of the frames' noise levels on white noise, skips non-finite values, says 1
// when there is no noise, and a farm's blocks of rows give the bits of a whole run;
// the modes' scales (frame_scale_factors, of Σ d²) recover the root of each
// frame's energy over the mean.
#include "core/common/error.h"
#include "core/denoise/frame_noise.h"
#include "core/denoise/stage_task.h"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;

namespace {

// `frames` frames of width × height × channels; frame t has Gaussian noise of sd levels[t] around `base`.
struct NoisyShot {
    int width, height, channels, frames;
    std::vector<float> data;
    NoisyShot(int w, int h, int c, const std::vector<double>& levels, unsigned seed)
        : width(w), height(h), channels(c), frames(static_cast<int>(levels.size())),
          data(static_cast<size_t>(w) * h * c * levels.size())
    {
        std::mt19937 generator(seed);
        std::normal_distribution<double> normal(0.0, 1.0);
        const size_t per_frame = static_cast<size_t>(w) * h * c;
        for (int t = 0; t < frames; ++t)
            for (size_t i = 0; i < per_frame; ++i)
                data[t * per_frame + i] =
                    static_cast<float>(0.5 + levels[static_cast<size_t>(t)] * normal(generator));
    }
    std::int64_t per_frame() const { return static_cast<std::int64_t>(width) * height * channels; }
    // The per-row sums of rows [row_begin, row_end), as a stream's first read of them finds them.
    std::vector<double> row_sums(int row_begin, int row_end, RowMeasure measure = RowMeasure::Absolute) const
    {
        const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
        lowrank::BandView band{data.data() + row_begin * row_samples, (row_end - row_begin) * row_samples,
                               frames, per_frame()};
        std::vector<double> sums(static_cast<size_t>(row_end - row_begin) * frames);
        row_roughness(band, width, channels, row_end - row_begin, sums.data(), measure);
        return sums;
    }
};

} // namespace

TEST_CASE("frame noise: a row's roughness is the sum of |x - (left + right)/2| over its finite triples")
{
    // One channel, width 5, one frame: 0 2 0 2 0 -> |2 - 0| + |0 - 2| + |2 - 0| = 6.
    std::vector<float> row{0, 2, 0, 2, 0};
    double sum = -1;
    row_roughness({row.data(), 5, 1, 5}, 5, 1, 1, &sum);
    CHECK(sum == 6.0);
    row[1] = std::numeric_limits<float>::quiet_NaN(); // the triples centred on 1 and 2 are skipped
    row_roughness({row.data(), 5, 1, 5}, 5, 1, 1, &sum);
    CHECK(sum == 2.0);
    row[1] = 2, row[4] = std::numeric_limits<float>::infinity();
    row_roughness({row.data(), 5, 1, 5}, 5, 1, 1, &sum);
    CHECK(sum == 4.0);
}

TEST_CASE("frame noise: on white noise the factors are the frames' noise levels over their mean")
{
    const std::vector<double> levels{0.05, 0.1, 0.2, 0.05, 0.1};
    const NoisyShot shot(96, 64, 3, levels, 7);
    const std::vector<double> factors =
        frame_noise_factors(roughness_blocks(shot.row_sums(0, 64).data(), shot.frames, 0, 64), shot.frames);
    REQUIRE(factors.size() == levels.size());
    const double mean = (0.05 + 0.1 + 0.2 + 0.05 + 0.1) / 5;
    for (size_t t = 0; t < levels.size(); ++t) {
        CAPTURE(t);
        CHECK(factors[t] == doctest::Approx(levels[t] / mean).epsilon(0.02));
    }
}

TEST_CASE("frame noise: on white noise the modes' scales are the root of each frame's energy over the mean")
{
    // Levels σ_t: the scale is σ_t / sqrt(mean σ²), what whitens the frames' energy.
    const std::vector<double> levels{0.05, 0.1, 0.2, 0.05, 0.1};
    const NoisyShot shot(96, 64, 3, levels, 7);
    const std::vector<double> scales = frame_scale_factors(
        roughness_blocks(shot.row_sums(0, 64, RowMeasure::Squared).data(), shot.frames, 0, 64), shot.frames);
    REQUIRE(scales.size() == levels.size());
    const double mean_square = (0.0025 + 0.01 + 0.04 + 0.0025 + 0.01) / 5;
    for (size_t t = 0; t < levels.size(); ++t) {
        CAPTURE(t);
        CHECK(std::abs(scales[t] / (levels[t] / std::sqrt(mean_square)) - 1.0) <
              0.04); // 18432 samples a frame
    }
}

TEST_CASE("frame noise: a shot without noise has factor 1 in every frame")
{
    const NoisyShot shot(16, 8, 1, {0.0, 0.0, 0.0}, 1);
    const std::vector<double> factors =
        frame_noise_factors(roughness_blocks(shot.row_sums(0, 8).data(), shot.frames, 0, 8), shot.frames);
    CHECK(factors == std::vector<double>{1.0, 1.0, 1.0});
}

TEST_CASE("frame noise: statistics tasks' blocks give the bits of the whole run's")
{
    const NoisyShot shot(40, 150, 3, {0.1, 0.3, 0.2, 0.05}, 3);
    const std::vector<double> whole = roughness_blocks(shot.row_sums(0, 150).data(), shot.frames, 0, 150);
    std::vector<double> joined = roughness_blocks(shot.row_sums(0, 64).data(), shot.frames, 0, 64);
    const std::vector<double> rest = roughness_blocks(shot.row_sums(64, 150).data(), shot.frames, 64, 150);
    joined.insert(joined.end(), rest.begin(), rest.end());
    CHECK(joined == whole); // exact: the same sums in the same order
    CHECK(whole.size() == static_cast<size_t>(stage_blocks(150)) * shot.frames);
    CHECK_THROWS_AS(roughness_blocks(shot.row_sums(10, 64).data(), shot.frames, 10, 64), Error);
    CHECK_THROWS_AS(frame_noise_factors({1.0, 2.0, 3.0}, 2), Error);
}
