// Blending re-rendered values into the denoised layer: weight 0 leaves bits
// alone, weight 1 takes the render by its inverse-variance share, the new sigma
// is the true standard error of the blend of two independent estimates, and a
// re-render noisier than the denoised value never makes the pixel worse.
#include "core/refine/blend.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

using namespace modestack::refine;

TEST_CASE("weight 0 keeps the bits, weight 1 takes a much better render almost whole")
{
    std::vector<float> weights{0.0f, 1.0f};
    std::vector<float> value{0.1f, NAN, 0.3f, 1, 2, 3};
    std::vector<float> sigma{0.5f, 0.5f, 0.5f, 9, 9, 9};
    std::vector<float> rendered{7, 7, 7, 4, 5, 6}, variance{1, 1, 1, 0.04f, 0.09f, 0.16f};
    std::vector<float> before = value;
    blend_refined(weights.data(), 2, 3, rendered.data(), variance.data(), value.data(), sigma.data());
    CHECK(std::memcmp(value.data(), before.data(), 3 * sizeof(float)) == 0); // NaN included
    CHECK(sigma[0] == 0.5f);
    // The share s / (s + r): s = 81 (sigma 9), r = (0.04 + 0.09 + 0.16) / 3.
    const double share = 81.0 / (81.0 + 0.29 / 3);
    CHECK(value[3] == doctest::Approx(share * 4 + (1 - share) * 1).epsilon(1e-6));
    CHECK(value[5] == doctest::Approx(share * 6 + (1 - share) * 3).epsilon(1e-6));
    CHECK(sigma[4] ==
          doctest::Approx(std::sqrt(share * share * 0.09 + (1 - share) * (1 - share) * 81)).epsilon(1e-6));
}

TEST_CASE("the blended sigma matches the spread of blends of independent noisy estimates")
{
    std::mt19937 generator(1);
    const double truth = 0.8, sigma_denoised = 0.05, sigma_rendered = 0.02, feather = 0.35;
    const double w =
        feather * 25e-4 / (25e-4 + 4e-4); // the feather times the render's inverse-variance share
    std::normal_distribution<double> denoised_noise(0, sigma_denoised), rendered_noise(0, sigma_rendered);
    const int trials = 20000;
    std::vector<float> weights(trials, static_cast<float>(feather)), value(trials),
        sigma(trials, float(sigma_denoised));
    std::vector<float> rendered(trials), variance(trials, float(sigma_rendered * sigma_rendered));
    for (int i = 0; i < trials; ++i) {
        value[i] = float(truth + denoised_noise(generator));
        rendered[i] = float(truth + rendered_noise(generator));
    }
    blend_refined(weights.data(), trials, 1, rendered.data(), variance.data(), value.data(), sigma.data());
    double squared_error = 0;
    for (int i = 0; i < trials; ++i)
        squared_error += (value[i] - truth) * (value[i] - truth);
    double measured = std::sqrt(squared_error / trials);
    CHECK(sigma[0] == doctest::Approx(std::sqrt(w * w * 4e-4 + (1 - w) * (1 - w) * 25e-4)).epsilon(1e-5));
    CHECK(measured == doctest::Approx(sigma[0]).epsilon(0.03));
    CHECK(estimated_relative_mse(value.data(), sigma.data(), 1, 1, 0.1f) ==
          doctest::Approx(sigma[0] * sigma[0] / (value[0] * value[0] + 0.01)).epsilon(1e-6));
}

TEST_CASE("a re-render noisier than the denoised value makes the pixel better, never worse")
{
    std::mt19937 generator(2);
    const double truth = 0.5, sigma_denoised = 0.02, sigma_rendered = 0.05;
    std::normal_distribution<double> denoised_noise(0, sigma_denoised), rendered_noise(0, sigma_rendered);
    const int trials = 20000;
    std::vector<float> weights(trials, 1.0f), value(trials), sigma(trials, float(sigma_denoised));
    std::vector<float> rendered(trials), variance(trials, float(sigma_rendered * sigma_rendered));
    double before = 0, after = 0;
    for (int i = 0; i < trials; ++i) {
        value[i] = float(truth + denoised_noise(generator));
        rendered[i] = float(truth + rendered_noise(generator));
        before += (value[i] - truth) * (value[i] - truth);
    }
    blend_refined(weights.data(), trials, 1, rendered.data(), variance.data(), value.data(), sigma.data());
    for (int i = 0; i < trials; ++i)
        after += (value[i] - truth) * (value[i] - truth);
    // The inverse-variance blend: 1 / (1/4e-4 + 1/25e-4), below both.
    const double best = 1.0 / (1.0 / 4e-4 + 1.0 / 25e-4);
    CHECK(sigma[0] == doctest::Approx(std::sqrt(best)).epsilon(1e-5));
    CHECK(after < before);
    CHECK(std::sqrt(after / trials) == doctest::Approx(sigma[0]).epsilon(0.03));
}
