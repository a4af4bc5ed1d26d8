// The surface filter of object space on a synthetic corner: a floor and a wall of
// points with a smooth signal each (very different levels), temporal rank 1,
// white noise, and the rank-1 projection as the rebuild. SURE picks a width that
// lowers the error, nothing bleeds across the corner (the normals differ), sigma
// matches the actual error, a clean field is left as it is, and the result does
// not depend on the thread count; filtering the rebuild's coefficients once
// equals the Gaussian of every frame, and a correction's part outside the span
// of the rebuild's weights is kept as it is.
#include "core/objectspace/surface_filter.h"
#include "core/objectspace/surface_kernel.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

using namespace modestack;

namespace {

constexpr int kFrames = 16;
constexpr double kSpacing = 0.05;
constexpr double kNoise = 0.2;

struct Corner {
    objectspace::SurfaceSamples samples;
    std::vector<double> truth;   // per point (one channel), times the temporal profile
    std::vector<double> profile; // unit-length temporal mode
    std::vector<std::vector<float>> noisy, rebuilt, sigma;
};

// `blob`: a patch of the floor is 2 brighter in frames 7 and 8 only (content the
// rank-1 rebuild misses).
bool in_blob(const Corner& corner, std::size_t p)
{
    const float* at = corner.samples.positions.data() + 3 * p;
    return at[1] == 0.0f && at[0] > 0.4f && at[0] < 0.6f && at[2] > 0.4f && at[2] < 0.6f;
}

Corner make_corner(double noise, bool blob = false)
{
    Corner corner;
    corner.samples.spacing = kSpacing;
    for (int i = 0; i <= 20; ++i)
        for (int j = 0; j <= 20; ++j) {
            double a = i * kSpacing, b = j * kSpacing;
            // Floor y = 0 (normal +y), x, z in [0, 1]; wall x = 0 (normal +x), y, z in [0, 1].
            corner.samples.positions.insert(corner.samples.positions.end(),
                                            {float(a), 0.0f, float(b)});
            corner.samples.normals.insert(corner.samples.normals.end(), {0.0f, 1.0f, 0.0f});
            corner.truth.push_back(1.0 + 0.3 * a);
            corner.samples.positions.insert(corner.samples.positions.end(), {0.0f, float(a + 1e-3), float(b)});
            corner.samples.normals.insert(corner.samples.normals.end(), {1.0f, 0.0f, 0.0f});
            corner.truth.push_back(5.0);
        }
    double norm = 0;
    for (int t = 0; t < kFrames; ++t) {
        corner.profile.push_back(1.0 + 0.5 * std::sin(0.7 * t));
        norm += corner.profile.back() * corner.profile.back();
    }
    for (double& value : corner.profile)
        value /= std::sqrt(norm);
    std::mt19937 random(11);
    std::normal_distribution<double> gauss(0.0, noise);
    const std::size_t points = corner.truth.size();
    corner.noisy.assign(kFrames, std::vector<float>(points));
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t p = 0; p < points; ++p)
            corner.noisy[t][p] = static_cast<float>(corner.truth[p] * corner.profile[t] + gauss(random) +
                                                    (blob && in_blob(corner, p) && (t == 7 || t == 8) ? 2.0 : 0.0));
    // The rank-1 rebuild: projection on the known mode.
    corner.rebuilt.assign(kFrames, std::vector<float>(points));
    for (std::size_t p = 0; p < points; ++p) {
        double coefficient = 0;
        for (int t = 0; t < kFrames; ++t)
            coefficient += corner.noisy[t][p] * corner.profile[t];
        for (int t = 0; t < kFrames; ++t)
            corner.rebuilt[t][p] = static_cast<float>(coefficient * corner.profile[t]);
    }
    corner.sigma.assign(kFrames, std::vector<float>(points, 0.0f));
    return corner;
}

// Filters every frame of `corner` in place (values and sigma).
objectspace::SurfaceFilterChoice filter(Corner& corner, bool filter_on = true)
{
    objectspace::SurfaceShot shot;
    shot.read_noisy = [&](int t, float* destination) {
        std::copy(corner.noisy[t].begin(), corner.noisy[t].end(), destination);
    };
    for (int t = 0; t < kFrames; ++t) {
        shot.rebuilt.push_back(corner.rebuilt[t].data());
        shot.leverages.push_back(corner.profile[t] * corner.profile[t]);
    }
    shot.channels = 1;
    shot.frame_values = static_cast<std::int64_t>(corner.truth.size());
    objectspace::SurfaceFilterOptions options;
    options.widths = {0.75, 1.0, 1.5, 2.0, 3.0};
    options.filter = filter_on;
    options.kept_modes = 1;
    const objectspace::SurfaceFilter surface_filter(
        corner.samples, options, {corner.profile}, shot,
        objectspace::SurfaceFilter::window_neighbours(corner.samples, options));
    std::vector<std::vector<float>> values = corner.rebuilt;
    for (int t = 0; t < kFrames; ++t)
        surface_filter.frame(t, corner.noisy[t].data(), values[t].data(), corner.sigma[t].data());
    corner.rebuilt = values;
    return surface_filter.choice();
}

double rms_error(const Corner& corner, const std::vector<std::vector<float>>& values)
{
    double sum = 0;
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t p = 0; p < corner.truth.size(); ++p) {
            double error = values[t][p] - corner.truth[p] * corner.profile[t];
            sum += error * error;
        }
    return std::sqrt(sum / (kFrames * corner.truth.size()));
}

} // namespace

TEST_CASE("surface filter: SURE picks a width that lowers the error, without bleeding across the corner")
{
    Corner corner = make_corner(kNoise);
    const double before = rms_error(corner, corner.rebuilt);
    objectspace::SurfaceFilterChoice choice = filter(corner);
    const double after = rms_error(corner, corner.rebuilt);
    MESSAGE("width " << choice.width << " spacings, RMS error " << before << " -> " << after << "; "
                     << choice.reasoning);
    CHECK(choice.width > 0);
    CHECK(after < 0.5 * before);
    // SURE's risks are estimates of the mean squared error: the chosen one is close to the truth.
    const double chosen = choice.risks[static_cast<std::size_t>(
        std::find(choice.widths.begin(), choice.widths.end(), choice.width) - choice.widths.begin())];
    CHECK(chosen == doctest::Approx(after * after).epsilon(0.3));
    // The wall (level 5) next to the floor (level ~1): no point moved by more than the noise.
    double worst = 0;
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t p = 0; p < corner.truth.size(); ++p)
            worst = std::max(worst, std::abs(corner.rebuilt[t][p] - corner.truth[p] * corner.profile[t]));
    CHECK(worst < 0.25);
}

TEST_CASE("surface filter: sigma bounds the error and stands out where the modes miss content")
{
    for (bool filter_on : {false, true}) {
        Corner corner = make_corner(kNoise);
        filter(corner, filter_on);
        double predicted = 0, actual = 0;
        for (int t = 0; t < kFrames; ++t)
            for (std::size_t p = 0; p < corner.truth.size(); ++p) {
                predicted += static_cast<double>(corner.sigma[t][p]) * corner.sigma[t][p];
                double error = corner.rebuilt[t][p] - corner.truth[p] * corner.profile[t];
                actual += error * error;
            }
        // As in image space (lowrank/confidence.h) sigma is conservative: its bias
        // term keeps the positive part of the windowed mean residual's noise.
        MESSAGE("filter " << filter_on << ": mean sigma^2 " << predicted / (kFrames * corner.truth.size())
                          << ", mean squared error " << actual / (kFrames * corner.truth.size()));
        CHECK(predicted >= actual);
    }
    Corner blob = make_corner(kNoise, true);
    filter(blob);
    double inside = 0, outside = 0, inside_count = 0, outside_count = 0;
    for (std::size_t p = 0; p < blob.truth.size(); ++p)
        (in_blob(blob, p) ? inside : outside) += blob.sigma[7][p], (in_blob(blob, p) ? inside_count : outside_count) += 1;
    MESSAGE("frame 7 mean sigma: in the blob " << inside / inside_count << ", elsewhere " << outside / outside_count);
    CHECK(inside / inside_count > 5 * outside / outside_count);
}

TEST_CASE("surface filter: a clean field is not filtered and keeps its values, and threads do not matter")
{
    Corner clean = make_corner(0.0);
    std::vector<std::vector<float>> before = clean.rebuilt;
    objectspace::SurfaceFilterChoice choice = filter(clean);
    CHECK(choice.width == 0);
    CHECK(clean.rebuilt == before);

    Corner one = make_corner(kNoise), two = make_corner(kNoise);
    tbb::task_arena(1).execute([&] { filter(one); });
    tbb::task_arena(2).execute([&] { filter(two); });
    CHECK(one.rebuilt == two.rebuilt);
    CHECK(one.sigma == two.sigma);

    Corner off = make_corner(kNoise);
    before = off.rebuilt;
    CHECK(filter(off, false).width == 0);
    CHECK(off.rebuilt == before);
}

TEST_CASE("surface filter: filtering the coefficients once is filtering every frame, and what lies outside "
          "the weights stays as it is")
{
    Corner corner = make_corner(kNoise);
    // A correction outside the rank-1 span (as --non-negative makes) on a few points of frame 5.
    std::vector<std::vector<float>> outside(kFrames, std::vector<float>(corner.truth.size(), 0.0f));
    for (std::size_t p = 0; p < corner.truth.size(); p += 97)
        outside[5][p] = 0.5f, corner.rebuilt[5][p] += 0.5f;
    const std::vector<std::vector<float>> rebuilt = corner.rebuilt;
    const objectspace::SurfaceFilterChoice choice = filter(corner);
    REQUIRE(choice.width > 0);
    // Frame by frame, the Gaussian of the chosen width over the brute-force
    // neighbours (normals agreeing) of each value's part in the span of the
    // weights (c_q Q_t), plus its own part outside that span as it was.
    const double sigma = choice.width * kSpacing, reach = objectspace::kReachInSigmas * sigma;
    const float* x = corner.samples.positions.data();
    const float* n = corner.samples.normals.data();
    const std::size_t points = corner.truth.size();
    std::vector<double> coefficient(points, 0.0);
    for (std::size_t p = 0; p < points; ++p)
        for (int t = 0; t < kFrames; ++t)
            coefficient[p] += rebuilt[t][p] * corner.profile[t];
    double worst = 0, largest_outside = 0;
    for (std::size_t p = 0; p < points; ++p) {
        std::vector<std::pair<std::size_t, double>> weights;
        double total = 0;
        for (std::size_t q = 0; q < points; ++q) {
            const float cosine =
                n[3 * p] * n[3 * q] + n[3 * p + 1] * n[3 * q + 1] + n[3 * p + 2] * n[3 * q + 2];
            const float ex = x[3 * p] - x[3 * q], ey = x[3 * p + 1] - x[3 * q + 1],
                        ez = x[3 * p + 2] - x[3 * q + 2];
            const float d2 = ex * ex + ey * ey + ez * ez;
            if (q != p && (cosine < 0.9f || d2 > static_cast<float>(reach * reach)))
                continue;
            const double weight = q == p ? 1.0 : std::exp(-0.5 * d2 / (sigma * sigma));
            weights.emplace_back(q, weight), total += weight;
        }
        for (int t = 0; t < kFrames; ++t) {
            const double own_outside = rebuilt[t][p] - coefficient[p] * corner.profile[t];
            largest_outside = std::max(largest_outside, std::abs(own_outside));
            double expected = own_outside;
            for (const auto& [q, weight] : weights)
                expected += weight / total * coefficient[q] * corner.profile[t];
            worst = std::max(worst, std::abs(expected - corner.rebuilt[t][p]));
        }
    }
    CHECK(largest_outside > 0.4); // the correction is mostly outside the span
    MESSAGE("width " << choice.width << ": largest difference from the frame-by-frame filter " << worst);
    CHECK(worst < 1e-5);
}
