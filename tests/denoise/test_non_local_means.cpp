// The non-local means candidate (core/denoise/non_local_means.h): a constant
// stays exact, a hard edge is kept where a box of the same reach blurs it, and
// the divergence it reports for SURE is the filter's true one on Gaussian noise
// (checked against a Monte-Carlo finite difference, E[b·(f(y + εb) − f(y))]/ε).
#include "core/denoise/non_local_means.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack::denoise;

namespace {

struct Image {
    int width = 40, height = 32, channels = 3;
    std::vector<float> values, variance;
    size_t at(int x, int y, int c) const { return (static_cast<size_t>(y) * width + x) * channels + c; }
    NonLocalInput input() const { return {width, height, channels, values.data(), 0}; }
    // The filter at every pixel: values and divergence, laid out like `values`.
    void filter(std::vector<float>& result, std::vector<float>& divergence) const
    {
        result.resize(values.size()), divergence.resize(values.size());
        std::vector<double> scratch;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                non_local_means(input(), x, y, &variance[at(x, y, 0)], &result[at(x, y, 0)],
                                &divergence[at(x, y, 0)], scratch);
    }
};

// A step (0.1 left of x = 20, 0.6 right of it) with Gaussian noise of deviation `noise`.
Image step(float noise, unsigned seed)
{
    Image image;
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, noise);
    const size_t samples = static_cast<size_t>(image.width) * image.height * image.channels;
    image.values.resize(samples), image.variance.assign(samples, noise * noise);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c)
                image.values[image.at(x, y, c)] = (x < 20 ? 0.1f : 0.6f) + normal(generator);
    return image;
}

} // namespace

TEST_CASE("non-local means: a constant is kept exactly, with every neighbour's full weight")
{
    Image image;
    const size_t samples = static_cast<size_t>(image.width) * image.height * image.channels;
    image.values.assign(samples, 0.25f), image.variance.assign(samples, 0.01f);
    std::vector<float> values, divergence;
    image.filter(values, divergence);
    for (float value : values)
        CHECK(value == doctest::Approx(0.25f));
    // In the middle all 7×7 neighbours count alike, and the divergence is the
    // centre's weight alone (no neighbour's weight moves with it).
    CHECK(divergence[image.at(20, 16, 0)] == doctest::Approx(1.0 / 49));
}

TEST_CASE("non-local means: a hard edge stays hard where a box of the same reach blurs it")
{
    const Image image = step(0.03f, 5);
    std::vector<float> values, divergence;
    image.filter(values, divergence);
    // The pixels either side of the edge, in the middle rows: within a few noise
    // deviations of their own side (a 7×7 box would give ~0.31 and ~0.39).
    for (int y = 8; y < 24; ++y) {
        CAPTURE(y);
        CHECK(std::abs(values[image.at(19, y, 0)] - 0.1f) < 0.05f);
        CHECK(std::abs(values[image.at(20, y, 0)] - 0.6f) < 0.05f);
    }
}

TEST_CASE("non-local means: the divergence is the filter's own, against a Monte-Carlo finite difference")
{
    double analytic = 0, measured = 0;
    const double epsilon = 1e-3;
    for (unsigned seed = 1; seed <= 3; ++seed) {
        const Image image = step(0.1f, seed);
        std::vector<float> values, divergence;
        image.filter(values, divergence);
        Image moved = image;
        std::mt19937 generator(100 + seed);
        std::normal_distribution<double> normal(0.0, 1.0);
        std::vector<double> direction(image.values.size());
        for (size_t i = 0; i < direction.size(); ++i) {
            direction[i] = normal(generator);
            moved.values[i] = static_cast<float>(image.values[i] + epsilon * direction[i]);
        }
        std::vector<float> moved_values, unused;
        moved.filter(moved_values, unused);
        for (size_t i = 0; i < values.size(); ++i) {
            analytic += divergence[i];
            measured += direction[i] * (static_cast<double>(moved_values[i]) - values[i]) / epsilon;
        }
    }
    CAPTURE(analytic);
    CAPTURE(measured);
    // The perturbation is rounded to float: ε = 1e-3 on values ~0.5 keeps ~4 digits.
    CHECK(measured == doctest::Approx(analytic).epsilon(0.05));
    CHECK(analytic > 0);
}
