// The surface neighbours against a brute-force search: random points on two
// faces of a box (some at negative coordinates, so the cell keys' offset
// matters) and a few with tilted normals; every point's list is itself first,
// then exactly the points within the radius whose normals agree, nearest first;
// count_within is a prefix; and the lists do not depend on the thread count.
// The cells (the wide kernels' visits) give the same neighbours, each point
// visited once, independent of the threads. The Gaussian: 1 at the point,
// falling with distance, cut at kReachInSigmas.
#include "core/objectspace/surface_cells.h"
#include "core/objectspace/surface_kernel.h"
#include "core/objectspace/surface_neighbours.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

using namespace modestack;
using objectspace::SurfaceNeighbours;
using objectspace::SurfaceSamples;

namespace {

constexpr double kMinCosine = 0.9;

SurfaceSamples random_box_faces(int count, unsigned seed)
{
    SurfaceSamples samples;
    samples.spacing = 0.05;
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> along(-0.6f, 0.4f);
    for (int i = 0; i < count; ++i) {
        const float a = along(random), b = along(random);
        switch (i % 3) {
        case 0: // floor y = -0.2, normal +y
            samples.positions.insert(samples.positions.end(), {a, -0.2f, b});
            samples.normals.insert(samples.normals.end(), {0.0f, 1.0f, 0.0f});
            break;
        case 1: // wall x = -0.3, normal +x
            samples.positions.insert(samples.positions.end(), {-0.3f, a, b});
            samples.normals.insert(samples.normals.end(), {1.0f, 0.0f, 0.0f});
            break;
        default: { // on the floor, normal tilted by 20° (cosine 0.94 with the floor's: still agrees)
            const float angle = 20.0f * 3.14159265f / 180.0f;
            samples.positions.insert(samples.positions.end(), {a, -0.2f, b});
            samples.normals.insert(samples.normals.end(), {std::sin(angle), std::cos(angle), 0.0f});
        }
        }
    }
    return samples;
}

// Point p's neighbours by brute force, with the list's float arithmetic: nearest
// first (ties by id), p itself first.
std::vector<std::pair<float, std::int64_t>> brute_force(const SurfaceSamples& samples, std::int64_t p, double radius)
{
    const float* x = samples.positions.data();
    const float* n = samples.normals.data();
    std::vector<std::pair<float, std::int64_t>> found;
    for (std::int64_t q = 0; q < samples.count(); ++q) {
        if (q == p)
            continue;
        float cosine = n[3 * p] * n[3 * q] + n[3 * p + 1] * n[3 * q + 1] + n[3 * p + 2] * n[3 * q + 2];
        float ex = x[3 * p] - x[3 * q], ey = x[3 * p + 1] - x[3 * q + 1], ez = x[3 * p + 2] - x[3 * q + 2];
        float d2 = ex * ex + ey * ey + ez * ez;
        if (cosine >= kMinCosine && d2 <= static_cast<float>(radius * radius))
            found.emplace_back(d2, q);
    }
    std::sort(found.begin(), found.end());
    found.insert(found.begin(), {0.0f, p});
    return found;
}

} // namespace

TEST_CASE("surface neighbours: exactly the brute-force neighbours, nearest first, itself first")
{
    const SurfaceSamples samples = random_box_faces(1500, 3);
    const double radius = 0.08;
    const SurfaceNeighbours neighbours(samples, radius, kMinCosine);
    REQUIRE(neighbours.count() == samples.count());
    std::int64_t total = 0;
    for (std::int64_t p = 0; p < samples.count(); ++p) {
        const auto expected = brute_force(samples, p, radius);
        REQUIRE(neighbours.size(p) == static_cast<std::int64_t>(expected.size()));
        for (std::size_t n = 0; n < expected.size(); ++n) {
            CHECK(neighbours.ids(p)[n] == expected[n].second);
            CHECK(neighbours.distances_squared(p)[n] == expected[n].first);
        }
        // The wall's points and the floor's never meet (their normals are 90° apart).
        for (std::int64_t n = 0; n < neighbours.size(p); ++n)
            CHECK((neighbours.ids(p)[n] % 3 == 1) == (p % 3 == 1));
        // count_within: the prefix within a smaller radius.
        const double inner = 0.05;
        const auto within = brute_force(samples, p, inner);
        CHECK(neighbours.count_within(p, inner) == static_cast<int>(within.size()));
        total += neighbours.size(p);
    }
    CHECK(neighbours.mean_size() == doctest::Approx(static_cast<double>(total) / samples.count()));
    CHECK(neighbours.mean_size() > 3); // the test means something: points have neighbours
}

TEST_CASE("surface neighbours: the same lists for 1 and 2 threads")
{
    const SurfaceSamples samples = random_box_faces(3000, 5);
    std::vector<std::int64_t> one, two;
    auto lists = [&](std::vector<std::int64_t>& out) {
        const SurfaceNeighbours neighbours(samples, 0.07, kMinCosine);
        for (std::int64_t p = 0; p < samples.count(); ++p)
            out.insert(out.end(), neighbours.ids(p), neighbours.ids(p) + neighbours.size(p));
    };
    tbb::task_arena(1).execute([&] { lists(one); });
    tbb::task_arena(2).execute([&] { lists(two); });
    CHECK(one == two);
}

TEST_CASE("surface cells: every point visited once with exactly the brute-force neighbours, itself first")
{
    const SurfaceSamples samples = random_box_faces(1500, 9);
    const double radius = 0.09;
    const objectspace::SurfaceCells cells(samples, radius, kMinCosine);
    std::vector<std::vector<std::pair<float, std::int64_t>>> seen(static_cast<std::size_t>(samples.count()));
    std::vector<int> visits(static_cast<std::size_t>(samples.count()), 0);
    cells.for_each_point([&](std::int64_t p, const std::vector<objectspace::SurfaceNeighbour>& neighbours) {
        ++visits[static_cast<std::size_t>(p)];
        REQUIRE(!neighbours.empty());
        CHECK(neighbours.front().id == p);
        for (const objectspace::SurfaceNeighbour& neighbour : neighbours)
            seen[static_cast<std::size_t>(p)].emplace_back(neighbour.distance_squared, neighbour.id);
    });
    std::int64_t total = 0;
    for (std::int64_t p = 0; p < samples.count(); ++p) {
        CHECK(visits[static_cast<std::size_t>(p)] == 1);
        auto got = seen[static_cast<std::size_t>(p)];
        std::sort(got.begin() + 1, got.end()); // the cells' order is theirs; the set is the test
        CHECK(got == brute_force(samples, p, radius));
        total += static_cast<std::int64_t>(got.size());
    }
    CHECK(static_cast<double>(total) / samples.count() > 3); // points have neighbours
}

TEST_CASE("surface cells: the same neighbours in the same order for 1 and 2 threads")
{
    const SurfaceSamples samples = random_box_faces(3000, 5);
    auto lists = [&] {
        std::vector<std::vector<std::int64_t>> out(static_cast<std::size_t>(samples.count()));
        objectspace::SurfaceCells(samples, 0.07, kMinCosine)
            .for_each_point(
                [&](std::int64_t p, const std::vector<objectspace::SurfaceNeighbour>& neighbours) {
                    for (const objectspace::SurfaceNeighbour& neighbour : neighbours)
                        out[static_cast<std::size_t>(p)].push_back(neighbour.id);
                });
        return out;
    };
    std::vector<std::vector<std::int64_t>> one, two;
    tbb::task_arena(1).execute([&] { one = lists(); });
    tbb::task_arena(2).execute([&] { two = lists(); });
    CHECK(one == two);
}

TEST_CASE("surface kernel: 1 at the point, a Gaussian of the distance, cut at its reach")
{
    const double width = 0.5, spacing = 0.05, sigma = width * spacing;
    const objectspace::SurfaceGaussian gaussian = objectspace::surface_gaussian(width, spacing);
    CHECK(gaussian.weight(0.0f) == 1.0);
    for (double distance : {0.3 * sigma, sigma, 2 * sigma, 2.99 * sigma})
        CHECK(gaussian.weight(static_cast<float>(distance * distance)) ==
              doctest::Approx(std::exp(-0.5 * distance * distance / (sigma * sigma))).epsilon(1e-6));
    const double reach = objectspace::kReachInSigmas * sigma;
    CHECK(gaussian.weight(static_cast<float>(1.01 * reach * 1.01 * reach)) == 0.0);
}
