// The object-space bake and lookup: in a white furnace the light arriving at every
// point after two or more bounces is e·a / (1 − a); bakes are bit-identical for
// any thread count; the error falls as 1/√spp (and DiffIndVar bounds it); and the PointLookup layer of a
// frame names valid points with weights summing to one, whose interpolated bake
// matches the frame's own DiffInd on average.
#include "core/render/point_bake.h"
#include "core/render/render.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <vector>

using namespace modestack;
using render::PointBake;
using render::RenderOptions;
using render::SurfacePoints;

namespace {

PointBake bake(const scene::Scene& scene, const SurfacePoints& points, const RenderOptions& options, int frame = 1)
{
    PointBake result;
    render::bake_points(scene, frame, points, options, result, Progress::silent());
    return result;
}

RenderOptions bake_options(int spp)
{
    RenderOptions options;
    options.spp = spp;
    return options;
}

// Mean over the points of the furnace's ceiling and walls (not the floor: part of
// it lies under the box, in the dark) of the baked DiffInd, and its RMS deviation
// from `expected`.
void point_statistics(const PointBake& bake, const SurfacePoints& points, double expected, double& mean,
                      double& rms)
{
    double sum = 0, squares = 0, n = 0;
    std::vector<render::PointPlace> places = points.places();
    for (std::size_t p = 0; p < places.size(); ++p) {
        if (places[p].mesh < 1 || places[p].mesh > 5)
            continue;
        for (int c = 0; c < 3; ++c) {
            double value = bake.indirect.pixels[p * 3 + c];
            sum += value;
            squares += (value - expected) * (value - expected);
            n += 1;
        }
    }
    mean = sum / n;
    rms = std::sqrt(squares / n);
}

} // namespace

TEST_CASE("bake: in a white furnace every point receives e*a/(1-a) of indirect light")
{
    const float albedo = 0.5f, emission = 0.5f;
    scene::Scene furnace = scene::make_furnace_scene(albedo, emission);
    SurfacePoints points(furnace, 0.25, 1 << 24);
    RenderOptions options = bake_options(64);
    options.max_depth = 64;
    PointBake result = bake(furnace, points, options);
    double mean = 0, rms = 0;
    const double expected = emission * albedo / (1 - albedo);
    point_statistics(result, points, expected, mean, rms);
    MESSAGE("furnace bake: " << points.count() << " points, mean " << mean << " (expected " << expected
                             << "), RMS deviation " << rms);
    CHECK(std::abs(mean - expected) < 0.01);
    CHECK(rms < 0.05);
    // Padding after the last point stays zero.
    for (std::size_t i = static_cast<std::size_t>(points.count()) * 3; i < result.indirect.pixels.size(); ++i)
        REQUIRE(result.indirect.pixels[i] == 0.0f);
}

TEST_CASE("bake: the error at a point falls as 1/sqrt(spp) and the variance layer predicts it")
{
    scene::Scene furnace = scene::make_furnace_scene(0.5f, 0.5f);
    SurfacePoints points(furnace, 0.2, 1 << 24);
    double rms4 = 0, rms64 = 0, mean = 0;
    PointBake low = bake(furnace, points, bake_options(4));
    PointBake high = bake(furnace, points, bake_options(64));
    point_statistics(low, points, 0.5, mean, rms4);
    point_statistics(high, points, 0.5, mean, rms64);
    MESSAGE("RMS error at 4 spp " << rms4 << ", at 64 spp " << rms64 << " (ratio " << rms4 / rms64 << ", expected 4)");
    CHECK(rms4 / rms64 > 3.0);
    CHECK(rms4 / rms64 < 5.5);
    // At 64 spp the per-point variance estimates are steady enough to bound the
    // error: from above, since the sample variance ignores what the stratified
    // (Owen-scrambled Sobol) samples gain over independent ones.
    double predicted = 0, n = 0;
    std::vector<render::PointPlace> places = points.places();
    for (std::size_t p = 0; p < places.size(); ++p)
        if (places[p].mesh >= 1 && places[p].mesh <= 5)
            for (int c = 0; c < 3; ++c, n += 1)
                predicted += high.variance.pixels[p * 3 + c];
    predicted = std::sqrt(predicted / n);
    MESSAGE("RMS error predicted by DiffIndVar at 64 spp: " << predicted);
    CHECK(predicted >= rms64);
    CHECK(predicted < 2 * rms64);
}

TEST_CASE("bake: bit-identical for one and two threads")
{
    scene::Scene room = scene::make_builtin_scene("flythrough", 5);
    SurfacePoints points(room, 0.15, 1 << 24);
    RenderOptions options = bake_options(2);
    PointBake one, two;
    tbb::task_arena(1).execute([&] { one = bake(room, points, options, 5); });
    tbb::task_arena(2).execute([&] { two = bake(room, points, options, 5); });
    REQUIRE(one.indirect.pixels.size() == two.indirect.pixels.size());
    CHECK(std::memcmp(one.indirect.pixels.data(), two.indirect.pixels.data(),
                      one.indirect.pixels.size() * sizeof(float)) == 0);
    CHECK(std::memcmp(one.variance.pixels.data(), two.variance.pixels.data(),
                      one.variance.pixels.size() * sizeof(float)) == 0);
    CHECK(one.stats.rays == two.stats.rays);
    CHECK(one.stats.paths == points.count() * 2);
}

TEST_CASE("lookup: each pixel names valid points whose interpolated bake matches the frame's DiffInd")
{
    scene::Scene room = scene::make_builtin_scene("static", 1);
    SurfacePoints points(room, 0.06, 1 << 24);
    RenderOptions options = bake_options(64);
    options.width = 40;
    options.height = 30;
    render::FrameAovs frame;
    render::render_frame(room, 1, options, nullptr, frame, Progress::silent(), &points);
    REQUIRE(frame.point_lookup.channels == 2 * render::kLookupPoints);
    PointBake baked = bake(room, points, options);
    double frame_sum = 0, lookup_sum = 0;
    for (int y = 0; y < options.height; ++y)
        for (int x = 0; x < options.width; ++x) {
            const float* lookup = frame.point_lookup.at(x, y);
            double weights = 0, value = 0;
            for (int k = 0; k < render::kLookupPoints; ++k) {
                float id = lookup[k], weight = lookup[render::kLookupPoints + k];
                if (weight == 0) {
                    CHECK(id == -1.0f);
                    continue;
                }
                REQUIRE(id >= 0);
                REQUIRE(id < static_cast<float>(points.count()));
                CHECK(id == std::floor(id));
                weights += weight;
                value += weight * baked.indirect.pixels[static_cast<std::size_t>(id) * 3 + 1];
            }
            CHECK(weights == doctest::Approx(1.0).epsilon(1e-5));
            frame_sum += frame.diffuse_indirect.at(x, y)[1];
            lookup_sum += value;
        }
    // Both estimate the same light: their frame means agree within noise and
    // the lattice's interpolation (a few percent at 64 spp).
    MESSAGE("mean DiffInd.G: frame " << frame_sum / 1200 << ", from the points " << lookup_sum / 1200);
    CHECK(lookup_sum == doctest::Approx(frame_sum).epsilon(0.06));
}
