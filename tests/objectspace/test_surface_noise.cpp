// The noise level of surface points: on a smooth rank-1 field with white noise of
// a known standard deviation per channel, rebuilt by projection on its temporal
// mode, s² comes out as the noise's variance (the residual keeps F − N degrees
// of freedom); without noise it is 0.
#include "core/objectspace/surface_neighbours.h"
#include "core/objectspace/surface_noise.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

using namespace modestack;

namespace {

constexpr int kFrames = 20;

struct Field {
    objectspace::SurfaceSamples samples;
    std::vector<std::vector<float>> noisy, rebuilt;
};

// A 40 × 40 lattice on the floor, two channels with noise `sigma[c]`, rebuilt by
// projection on the known unit temporal mode.
Field make_field(const double sigma[2])
{
    Field field;
    field.samples.spacing = 0.05;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j) {
            field.samples.positions.insert(field.samples.positions.end(),
                                           {float(i * 0.05), 0.0f, float(j * 0.05)});
            field.samples.normals.insert(field.samples.normals.end(), {0.0f, 1.0f, 0.0f});
        }
    const std::size_t points = static_cast<std::size_t>(field.samples.count());
    std::vector<double> mode(kFrames);
    double norm = 0;
    for (int t = 0; t < kFrames; ++t) {
        mode[t] = 1.0 + 0.4 * std::cos(0.5 * t);
        norm += mode[t] * mode[t];
    }
    for (double& value : mode)
        value /= std::sqrt(norm);
    std::mt19937 random(17);
    std::normal_distribution<double> gauss(0.0, 1.0);
    field.noisy.assign(kFrames, std::vector<float>(points * 2));
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t p = 0; p < points; ++p)
            for (int c = 0; c < 2; ++c)
                field.noisy[t][p * 2 + c] =
                    static_cast<float>((2.0 + 0.5 * c + 0.01 * p) * mode[t] + sigma[c] * gauss(random));
    field.rebuilt = field.noisy;
    for (std::size_t v = 0; v < points * 2; ++v) {
        double coefficient = 0;
        for (int t = 0; t < kFrames; ++t)
            coefficient += field.noisy[t][v] * mode[t];
        for (int t = 0; t < kFrames; ++t)
            field.rebuilt[t][v] = static_cast<float>(coefficient * mode[t]);
    }
    return field;
}

std::vector<double> noise_of(Field& field, double window)
{
    objectspace::SurfaceShot shot;
    shot.read_noisy = [&](int t, float* destination) {
        std::copy(field.noisy[t].begin(), field.noisy[t].end(), destination);
    };
    for (int t = 0; t < kFrames; ++t) {
        shot.rebuilt.push_back(field.rebuilt[t].data());
        shot.leverages.push_back(0.0);
    }
    shot.channels = 2;
    shot.frame_values = static_cast<std::int64_t>(field.noisy[0].size());
    const objectspace::SurfaceNeighbours neighbours(field.samples, window, 0.9);
    return objectspace::surface_noise_variance(neighbours, neighbours.counts_within(window), shot, 1);
}

} // namespace

TEST_CASE("surface noise: s² is the variance of white noise, per channel")
{
    const double sigma[2] = {0.1, 0.3};
    Field field = make_field(sigma);
    const std::vector<double> noise = noise_of(field, 2 * field.samples.spacing);
    REQUIRE(noise.size() == static_cast<std::size_t>(field.samples.count()) * 2);
    for (int c = 0; c < 2; ++c) {
        double mean = 0;
        for (std::size_t p = 0; p < noise.size() / 2; ++p)
            mean += noise[p * 2 + c];
        mean /= static_cast<double>(noise.size() / 2);
        MESSAGE("channel " << c << ": mean s² " << mean << ", noise variance " << sigma[c] * sigma[c]);
        CHECK(mean == doctest::Approx(sigma[c] * sigma[c]).epsilon(0.05));
    }
}

TEST_CASE("surface noise: 0 without noise")
{
    const double none[2] = {0.0, 0.0};
    Field field = make_field(none);
    for (double value : noise_of(field, 2 * field.samples.spacing))
        CHECK(value < 1e-10);
}
