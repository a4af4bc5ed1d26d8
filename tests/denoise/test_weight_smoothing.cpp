// `denoise --weight-smoothing` (weight_smoothing.h): the noise estimate finds
// the level of white noise; a straight ramp passes the local linear smoother
// unchanged; on noisy weights with a planted step the flicker drops several times
// while the step is found at its frame, keeps its height, and the values on one
// side of it do not depend on those on the other side (bit-identical); weights
// without noise are left alone; through the engine the rebuild of a noisy shot
// flickers less against the truth and a lighting switch stays at its frame.
#include "core/denoise/engine.h"
#include "core/denoise/weight_smoothing.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

constexpr int kFrames = 60, kStep = 30;
constexpr double kStepHeight = 0.5, kNoise = 0.02;

// A slow swing plus a step at kStep: the truth of the weights.
std::vector<double> true_weights()
{
    std::vector<double> values;
    for (int t = 0; t < kFrames; ++t)
        values.push_back(0.3 * std::sin(0.08 * t) + (t >= kStep ? kStepHeight : 0.0));
    return values;
}

std::vector<double> noisy(const std::vector<double>& truth, double noise, unsigned seed)
{
    std::mt19937 generator(seed);
    std::normal_distribution<double> normal(0.0, noise);
    std::vector<double> values = truth;
    for (double& value : values)
        value += normal(generator);
    return values;
}

// Mean squared error of the frame-to-frame changes against the truth's.
double weight_flicker(const std::vector<double>& values, const std::vector<double>& truth)
{
    double sum = 0;
    for (size_t t = 1; t < values.size(); ++t) {
        const double error = (values[t] - values[t - 1]) - (truth[t] - truth[t - 1]);
        sum += error * error;
    }
    return sum / static_cast<double>(values.size() - 1);
}

// Rank-2 light over `frames` frames (a slow drift and, from frame `switch_on`, a
// second light on the right half) plus Gaussian noise.
MemoryShot switch_shot(int frames, int switch_on, float noise, unsigned seed)
{
    const int width = 32, height = 24;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    for (int t = 0; t < frames; ++t) {
        std::vector<float> frame(std::size_t(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float value = (0.5f + 0.2f * std::sin(0.3f * x + c)) * (1.0f + 0.02f * t) +
                                        (t >= switch_on && x >= width / 2 ? 0.8f : 0.0f);
                    frame[(std::size_t(y) * width + x) * 3 + c] = value + noise * normal(generator);
                }
        shot.frames.push_back(frame);
    }
    return shot;
}

double shot_flicker(const std::vector<std::vector<float>>& values, const std::vector<std::vector<float>>& truth)
{
    double sum = 0;
    std::size_t count = 0;
    for (size_t t = 1; t < values.size(); ++t)
        for (size_t i = 0; i < values[t].size(); ++i, ++count) {
            const double error = (double(values[t][i]) - values[t - 1][i]) - (double(truth[t][i]) - truth[t - 1][i]);
            sum += error * error;
        }
    return sum / static_cast<double>(count);
}

// Mean over the right half's samples of frame t minus frame t − 1.
double right_half_change(const std::vector<std::vector<float>>& values, int t)
{
    const int width = 32, height = 24;
    double sum = 0;
    for (int y = 0; y < height; ++y)
        for (int x = width / 2; x < width; ++x)
            for (int c = 0; c < 3; ++c) {
                const size_t i = (size_t(y) * width + x) * 3 + c;
                sum += double(values[size_t(t)][i]) - values[size_t(t) - 1][i];
            }
    return sum / (height * (width / 2) * 3);
}

}  // namespace

TEST_CASE("weight smoothing: noise level, and a straight ramp passes the local linear fit unchanged")
{
    std::vector<double> zero(2000, 0.0);
    CHECK(weight_noise(noisy(zero, 0.05, 3)) == doctest::Approx(0.05).epsilon(0.08));
    std::vector<double> ramp;
    for (int t = 0; t < 40; ++t)
        ramp.push_back(0.2 - 0.013 * t);
    CHECK(weight_noise(ramp) < 1e-12);
    double trace = 0;
    const std::vector<double> fitted = smooth_pieces(ramp, 3.0, {17}, &trace);
    for (int t = 0; t < 40; ++t)
        CHECK(fitted[size_t(t)] == doctest::Approx(ramp[size_t(t)]).epsilon(1e-12));
    CHECK(trace > 1.0);  // a real smoother: far fewer degrees of freedom than 40
    CHECK(trace < 10.0);
    // Weights without noise are not touched.
    WeightSmoothingPlan plan;
    Eigen::MatrixXd clean(40, 1);
    for (int t = 0; t < 40; ++t)
        clean(t, 0) = ramp[size_t(t)];
    CHECK(smooth_temporal_weights(clean, {}, plan) == clean);
    CHECK(plan.modes.at(0).width == 0.0);
}

TEST_CASE("weight smoothing: flicker drops on noisy weights, a planted step stays at its frame with its height")
{
    const std::vector<double> truth = true_weights();
    double input_flicker = 0, output_flicker = 0;
    for (unsigned seed = 1; seed <= 10; ++seed) {
        CAPTURE(seed);
        const std::vector<double> values = noisy(truth, kNoise, seed);
        Eigen::MatrixXd weights(kFrames, 1);
        for (int t = 0; t < kFrames; ++t)
            weights(t, 0) = values[size_t(t)];
        WeightSmoothingPlan plan;
        const Eigen::MatrixXd smoothed = smooth_temporal_weights(weights, {}, plan);
        const ModeSmoothing& mode = plan.modes.at(0);
        CHECK(mode.noise == doctest::Approx(kNoise).epsilon(0.35));
        REQUIRE(mode.jumps == std::vector<int>{kStep});  // found exactly at its frame
        CHECK(mode.width >= 1.5);
        CHECK(mode.sure_gain > 0);
        std::vector<double> result(smoothed.data(), smoothed.data() + kFrames);
        input_flicker += weight_flicker(values, truth);
        output_flicker += weight_flicker(result, truth);
        // The step keeps its height to within the noise of a piece mean.
        CHECK(std::abs((result[kStep] - result[kStep - 1]) - kStepHeight) < 2.5 * kNoise);
        // Nothing crosses the step: changing every value after it leaves the ones
        // before it bit-identical, and the other way round.
        std::vector<double> changed = values;
        for (int t = kStep; t < kFrames; ++t)
            changed[size_t(t)] += 0.1 * std::cos(0.7 * t);
        const std::vector<double> left = smooth_pieces(changed, mode.width, mode.jumps);
        for (int t = 0; t < kStep; ++t)
            CHECK(left[size_t(t)] == result[size_t(t)]);
        changed = values;
        changed[0] -= 0.05;
        changed[kStep - 1] += 0.05;
        const std::vector<double> right = smooth_pieces(changed, mode.width, mode.jumps);
        for (int t = kStep; t < kFrames; ++t)
            CHECK(right[size_t(t)] == result[size_t(t)]);
    }
    MESSAGE("weight flicker against the truth: noisy " << input_flicker / 10 << ", smoothed " << output_flicker / 10);
    CHECK(output_flicker < input_flicker / 4);
}

TEST_CASE("weight smoothing through the engine: less flicker against the truth, a light switch stays at its frame")
{
    const int frames = 24, switch_on = 12;
    MemoryShot clean = switch_shot(frames, switch_on, 0.0f, 1);
    MemoryShot shot = switch_shot(frames, switch_on, 0.25f, 7);
    Settings settings;
    settings.outliers.fireflies = false;
    settings.mode_filter.enabled = false;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 5; // 3 modes of noise: their weights are pure noise
    MemorySink plain(shot.size), smoothed(shot.size);
    run_denoise(shot, plain, settings, Progress::silent());
    settings.weight_smoothing.enabled = true;
    const Report report = run_denoise(shot, smoothed, settings, Progress::silent());
    REQUIRE(report.weight_smoothing.modes.size() == 5);
    const double plain_flicker = shot_flicker(plain.rebuilt, clean.frames);
    const double smoothed_flicker = shot_flicker(smoothed.rebuilt, clean.frames);
    MESSAGE("rebuild flicker: plain " << plain_flicker << ", smoothed " << smoothed_flicker << "; MSE plain "
                                      << mean_square(plain.rebuilt, clean.frames) << ", smoothed "
                                      << mean_square(smoothed.rebuilt, clean.frames));
    CHECK(smoothed_flicker < 0.8 * plain_flicker);
    CHECK(mean_square(smoothed.rebuilt, clean.frames) <= mean_square(plain.rebuilt, clean.frames));
    // The switch is the largest change of the right half and keeps its size.
    const double clean_step = right_half_change(clean.frames, switch_on);
    CHECK(right_half_change(smoothed.rebuilt, switch_on) == doctest::Approx(clean_step).epsilon(0.05));
    for (int t = 1; t < frames; ++t)
        if (t != switch_on)
            CHECK(std::abs(right_half_change(smoothed.rebuilt, t)) < 0.1 * clean_step);
    // Sigma stays finite and positive.
    for (const auto& frame : smoothed.sigma)
        for (float value : frame)
            REQUIRE((std::isfinite(value) && value >= 0.0f));
}
