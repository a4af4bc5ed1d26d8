// The sample hash: determinism, range, stratification of each dimension pair
// (an Owen-scrambled Sobol (0,2)-sequence is a (0,m,2)-net for 2^m samples) and
// the fixed-seed switch.
#include "core/render/sampler.h"

#include <doctest/doctest.h>

#include <cmath>
#include <set>
#include <vector>

using modestack::render::PixelSampler;
using modestack::render::Sample2;

TEST_CASE("sampler: numbers lie in the unit interval and depend only on their coordinates")
{
    PixelSampler a(7, 3, false, 10, 20), b(7, 3, false, 10, 20);
    for (std::uint32_t pair = 0; pair < 8; ++pair)
        for (std::uint32_t index = 0; index < 64; ++index) {
            Sample2 s = a.get_2d(index, pair), t = b.get_2d(index, pair);
            CHECK(s.u >= 0.0f);
            CHECK(s.u < 1.0f);
            CHECK(s.v >= 0.0f);
            CHECK(s.v < 1.0f);
            CHECK(s.u == t.u);
            CHECK(s.v == t.v);
        }
}

TEST_CASE("sampler: 16 samples of every pair form a (0 4 2)-net")
{
    // Every elementary box of area 1/16 (1×16, 2×8, 4×4, 8×2, 16×1 grids) holds
    // exactly one point: the stratification that makes low spp converge well.
    for (int pixel = 0; pixel < 20; ++pixel) {
        PixelSampler sampler(1, 1, false, pixel, 3 * pixel);
        for (std::uint32_t pair = 0; pair < 10; ++pair) {
            std::vector<Sample2> points;
            for (std::uint32_t index = 0; index < 16; ++index)
                points.push_back(sampler.get_2d(index, pair));
            for (int log_columns = 0; log_columns <= 4; ++log_columns) {
                int columns = 1 << log_columns, rows = 16 / columns;
                std::set<int> boxes;
                for (Sample2 p : points)
                    boxes.insert(static_cast<int>(p.u * columns) * rows + static_cast<int>(p.v * rows));
                CHECK(boxes.size() == 16);
            }
        }
    }
}

TEST_CASE("sampler: pixels and pairs and seeds get different numbers and a fixed seed ignores the frame")
{
    PixelSampler base(1, 5, false, 4, 4);
    Sample2 reference = base.get_2d(0, 1);
    auto differs = [&](const PixelSampler& other, std::uint32_t pair) {
        Sample2 s = other.get_2d(0, pair);
        return s.u != reference.u || s.v != reference.v;
    };
    CHECK(differs(PixelSampler(1, 5, false, 5, 4), 1));
    CHECK(differs(PixelSampler(1, 5, false, 4, 5), 1));
    CHECK(differs(PixelSampler(2, 5, false, 4, 4), 1));
    CHECK(differs(PixelSampler(1, 6, false, 4, 4), 1));
    CHECK(differs(base, 2));
    PixelSampler fixed_a(1, 5, true, 4, 4), fixed_b(1, 6, true, 4, 4);
    for (std::uint32_t index = 0; index < 16; ++index) {
        CHECK(fixed_a.get_2d(index, 3).u == fixed_b.get_2d(index, 3).u);
        CHECK(fixed_a.get_2d(index, 3).v == fixed_b.get_2d(index, 3).v);
    }
}

TEST_CASE("sampler: the mean over pixels is uniform and the two coordinates are uncorrelated")
{
    double sum_u = 0, sum_v = 0, sum_uv = 0;
    const int count = 4096;
    for (int pixel = 0; pixel < count; ++pixel) {
        Sample2 s = PixelSampler(3, 1, false, pixel % 64, pixel / 64).get_2d(5, 7);
        sum_u += s.u;
        sum_v += s.v;
        sum_uv += static_cast<double>(s.u) * s.v;
    }
    CHECK(sum_u / count == doctest::Approx(0.5).epsilon(0.03));
    CHECK(sum_v / count == doctest::Approx(0.5).epsilon(0.03));
    // Covariance of two independent U(0,1): 0 (standard error ~ 1/12/√4096 ≈ 0.0013).
    CHECK(std::abs(sum_uv / count - (sum_u / count) * (sum_v / count)) < 0.006);
}
