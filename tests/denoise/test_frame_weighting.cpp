// Modes fitted to frames of uneven noise (core/denoise/frame_weighting.h): the
// Gram sums of X D⁻¹ are those of the scaled frames, a rank-N shot comes back
// exactly through A = D⁻¹ V and B = D V, the scales are floored, and through
// the engine a noise-free shot of rank 3 whose frames differ in brightness
// (so in roughness, and the scales are far from 1) is still recovered exactly,
// and merged parts' scales line up with the shot's frames.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/denoise/estimator_choice.h"
#include "core/denoise/frame_weighting.h"
#include "core/denoise/segments.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/confidence.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// P × F samples of rank 3 plus Gaussian noise of sd `noise`.
Eigen::MatrixXf low_rank_rows(int rows, int frames, float noise, unsigned seed)
{
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    Eigen::MatrixXf spatial(rows, 3), temporal(frames, 3);
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < 3; ++j)
            spatial(i, j) = normal(generator);
    for (int t = 0; t < frames; ++t)
        for (int j = 0; j < 3; ++j)
            temporal(t, j) = std::cos(0.4f * static_cast<float>((j + 1) * t)) + 0.1f * static_cast<float>(j);
    Eigen::MatrixXf x = spatial * temporal.transpose();
    for (int i = 0; i < rows; ++i)
        for (int t = 0; t < frames; ++t)
            x(i, t) += noise * normal(generator);
    return x;
}

lowrank::GramAccumulator gram_of(const Eigen::MatrixXf& x)
{
    lowrank::GramAccumulator gram(static_cast<int>(x.cols()));
    gram.add(lowrank::BandView{x.data(), x.rows(), static_cast<int>(x.cols()), x.rows()});
    return gram;
}

} // namespace

TEST_CASE("frame weighting: the scaled Gram sums are those of X D^-1, halves and frame sums included")
{
    const int frames = 9;
    const Eigen::MatrixXf x = low_rank_rows(4096, frames, 0.3f, 3);
    Eigen::VectorXd scales(frames);
    for (int t = 0; t < frames; ++t)
        scales[t] = 0.5 + 0.25 * t;
    Eigen::MatrixXf scaled = x;
    for (int t = 0; t < frames; ++t)
        scaled.col(t) /= static_cast<float>(scales[t]);
    const lowrank::GramAccumulator expected = gram_of(scaled);
    const lowrank::GramAccumulator found = scaled_gram(gram_of(x), scales);
    const double norm = expected.gram().norm();
    CHECK((found.gram() - expected.gram()).norm() < 1e-6 * norm);
    for (int half : {0, 1})
        CHECK((found.half_gram(half) - expected.half_gram(half)).norm() < 1e-6 * norm);
    CHECK((found.frame_sum() - expected.frame_sum()).norm() < 1e-5 * expected.frame_sum().norm());
    CHECK(found.rows() == expected.rows());
    // No scales: the sums as they were.
    CHECK(scaled_gram(gram_of(x), Eigen::VectorXd()).gram() == gram_of(x).gram());
    CHECK_THROWS_AS(scaled_gram(gram_of(x), Eigen::VectorXd::Ones(frames - 1)), Error);
}

TEST_CASE(
    "frame weighting: a rank-3 shot comes back exactly through D^-1 V and D V, and the leverages stay V's")
{
    const int frames = 12;
    const Eigen::MatrixXf x = low_rank_rows(2000, frames, 0.0f, 5);
    Eigen::VectorXd scales(frames);
    for (int t = 0; t < frames; ++t)
        scales[t] = t < 8 ? 0.3 : 2.5; // a light switched on in the last third
    const lowrank::Basis basis = lowrank::basis_from_gram(scaled_gram(gram_of(x), scales));
    const Eigen::MatrixXd modes = basis.temporal.leftCols(3);
    const Eigen::MatrixXd projection = projection_weights(modes, scales),
                          rebuild = rebuild_weights(modes, scales);
    const Eigen::MatrixXd samples = x.cast<double>();
    const Eigen::MatrixXd rebuilt = samples * projection * rebuild.transpose();
    CHECK((rebuilt - samples).norm() < 1e-6 * samples.norm()); // float samples
    const Eigen::VectorXd leverages = (rebuild.array() * projection.array()).rowwise().sum();
    const Eigen::VectorXd expected = modes.array().square().rowwise().sum();
    CHECK((leverages - expected).norm() < 1e-12);
    CHECK(lowrank::frame_noise_variance(scales, 0) == doctest::Approx(0.09));
    CHECK(lowrank::frame_noise_variance(Eigen::VectorXd(), 3) == 1.0);
}

TEST_CASE("frame weighting: a frame far quieter than the shot gets the smallest scale, not a vanishing one")
{
    const Eigen::VectorXd scales = frame_scales({0.0, 0.01, 0.5, 2.0});
    CHECK(scales[0] == kSmallestFrameScale);
    CHECK(scales[1] == kSmallestFrameScale);
    CHECK(scales[2] == 0.5);
    CHECK(scales[3] == 2.0);
    CHECK(frame_scales({}).size() == 0);
}

TEST_CASE("frame weighting: through the engine, a noise-free rank-3 shot with frames of very different "
          "roughness is recovered exactly")
{
    const int width = 40, height = 30, frames = 16;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    for (int t = 0; t < frames; ++t) {
        // Texture whose contrast grows 8-fold over the shot: the roughness, so the scales, follow it.
        const float contrast = 0.1f + 0.7f * static_cast<float>(t) / (frames - 1);
        const float fade = 1.0f + 0.3f * std::sin(0.5f * static_cast<float>(t));
        std::vector<float> frame(static_cast<size_t>(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    frame[(static_cast<size_t>(y) * width + x) * 3 + c] =
                        fade * (1.0f + 0.2f * std::cos(0.3f * y)) +
                        contrast * (((x + 2 * y + c) % 5) / 5.0f) +
                        (x < width / 2 ? 0.3f * std::sin(0.9f * static_cast<float>(t)) : 0.0f);
        shot.frames.push_back(frame);
    }
    Settings settings;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 3;
    settings.outliers.fireflies = false;
    MemorySink sink(shot.size);
    const Report report = run_denoise(shot, sink, settings, Progress::silent());
    REQUIRE(report.frame_scales.size() == static_cast<size_t>(frames));
    const auto [smallest, largest] =
        std::minmax_element(report.frame_scales.begin(), report.frame_scales.end());
    CHECK(*largest > 3 * *smallest);
    double error = 0, energy = 0;
    for (int t = 0; t < frames; ++t)
        for (size_t i = 0; i < shot.frames[static_cast<size_t>(t)].size(); ++i) {
            const double truth = shot.frames[static_cast<size_t>(t)][i];
            const double e = sink.rebuilt[static_cast<size_t>(t)][i] - truth;
            error += e * e, energy += truth * truth;
        }
    CHECK(std::sqrt(error / energy) < 1e-5);
}

TEST_CASE("frame weighting: merged parts' scales line up with the shot's frames, a part fitted to even noise "
          "counting 1 in each of its frames")
{
    Report measured, even, also_even;
    measured.shape.frames = 3;
    measured.frame_scales = {0.5, 1.0, 1.5};
    even.shape.frames = 2;
    CHECK(merge_reports({measured, even}).frame_scales == std::vector<double>{0.5, 1.0, 1.5, 1.0, 1.0});
    CHECK(merge_reports({even, measured}).frame_scales == std::vector<double>{1.0, 1.0, 0.5, 1.0, 1.5});
    also_even.shape.frames = 4;
    CHECK(merge_reports({even, also_even}).frame_scales.empty());
}

TEST_CASE(
    "frame weighting: the scales are measured on the input cleaned of fireflies, which the modes never see")
{
    // Even Gaussian noise in every frame; frame 5 also has 2 % fireflies 40× the
    // signal, which the firefly clamp removes before the Gram sums.
    const int width = 48, height = 32, frames = 16, fiery = 5;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(11);
    std::normal_distribution<float> normal(0.0f, 0.1f);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (int t = 0; t < frames; ++t) {
        std::vector<float> frame(static_cast<size_t>(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float value = 0.5f + 0.1f * std::sin(0.2f * static_cast<float>(x + t));
                    const bool firefly = t == fiery && c == 0 && uniform(generator) < 0.02f;
                    frame[(static_cast<size_t>(y) * width + x) * 3 + c] =
                        value + normal(generator) + (firefly ? 20.0f : 0.0f);
                }
        shot.frames.push_back(frame);
    }
    MemorySink sink(shot.size);
    Settings settings;
    settings.estimators =
        parse_estimators("rebuild,input,spatial"); // the choice reports its factors, as read
    const Report report = run_denoise(shot, sink, settings, Progress::silent());
    REQUIRE(report.frame_scales.size() == static_cast<size_t>(frames));
    REQUIRE(report.frame_noise_factors.size() == static_cast<size_t>(frames));
    REQUIRE(report.outliers.fireflies > 0);
    MESSAGE("frame " << fiery << ": scale " << report.frame_scales[fiery] << ", the choice's factor as read "
                     << report.frame_noise_factors[fiery]);
    CHECK(report.frame_noise_factors[fiery] > 2); // the fireflies as read
    // The clamp cuts a firefly to its pixel's threshold, not to the noise: some
    // energy stays (1.34 here; the choice's mean |d| of the frame as read: 3.1).
    CHECK(report.frame_scales[fiery] < 1.5);
    for (int t = 0; t < frames; ++t)
        if (t != fiery)
            CHECK(std::abs(report.frame_scales[static_cast<size_t>(t)] - 1.0) < 0.1);
}
