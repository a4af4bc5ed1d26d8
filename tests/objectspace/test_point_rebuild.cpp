// Pixels rebuilt from surface points: a pixel naming one point with weight 1 is
// that point, bit for bit; weights mix points linearly (sigma too); unused slots
// are skipped and a bad id is a bad-input error naming the file. And on a real
// render of a static camera at 1 spp, the points' own positions rebuilt through
// each pixel's PointLookup are the position the pixel sees: the lookup names the
// points around the very spot the pixel's sample hit.
#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/objectspace/point_rebuild.h"
#include "core/render/point_bake.h"
#include "core/render/render.h"
#include "core/render/surface_points.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace modestack;
using objectspace::kLookupChannels;
using render::kLookupPoints;

namespace {

// A lookup entry naming `ids` with `weights` (the rest unused: id −1, weight 0).
void set_entry(float* entry, const std::vector<float>& ids, const std::vector<float>& weights)
{
    for (int k = 0; k < kLookupPoints; ++k) {
        entry[k] = k < static_cast<int>(ids.size()) ? ids[k] : -1.0f;
        entry[kLookupPoints + k] = k < static_cast<int>(weights.size()) ? weights[k] : 0.0f;
    }
}

} // namespace

TEST_CASE("point rebuild: one point of weight 1 is that point, bit for bit")
{
    const int channels = 3, points = 50;
    std::mt19937 random(4);
    std::uniform_real_distribution<float> value(-2.0f, 9.0f);
    std::vector<float> values(points * channels), sigma(points * channels);
    for (std::size_t i = 0; i < values.size(); ++i)
        values[i] = value(random), sigma[i] = std::abs(value(random));
    const std::size_t pixels = 120;
    std::vector<float> lookup(pixels * kLookupChannels), rebuilt(pixels * channels), error(pixels * channels);
    for (std::size_t p = 0; p < pixels; ++p)
        set_entry(&lookup[p * kLookupChannels], {static_cast<float>((p * 7) % points)}, {1.0f});
    objectspace::rebuild_from_points(lookup.data(), pixels, values.data(), sigma.data(), channels, points, "f.exr",
                                     rebuilt.data(), error.data());
    for (std::size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < channels; ++c) {
            CHECK(rebuilt[p * channels + c] == values[(p * 7) % points * channels + c]);
            CHECK(error[p * channels + c] == sigma[(p * 7) % points * channels + c]);
        }
}

TEST_CASE("point rebuild: weights mix points linearly, unused slots are skipped, bad ids are errors")
{
    const int channels = 2;
    const std::vector<float> values{1, 10, 2, 20, 3, 30, 4, 40}, sigma{0.1f, 1, 0.2f, 2, 0.3f, 3, 0.4f, 4};
    std::vector<float> lookup(3 * kLookupChannels), rebuilt(3 * channels, -1.0f), error(3 * channels, -1.0f);
    set_entry(&lookup[0], {0, 1, 2, 3}, {0.1f, 0.2f, 0.3f, 0.4f});
    set_entry(&lookup[kLookupChannels], {3, 5e9f, 1}, {0.25f, 0.0f, 0.75f}); // weight 0: its id is not read
    set_entry(&lookup[2 * kLookupChannels], {}, {});                         // no sample saw albedo: 0
    objectspace::rebuild_from_points(lookup.data(), 3, values.data(), sigma.data(), channels, 4, "f.exr",
                                     rebuilt.data(), error.data());
    CHECK(rebuilt[0] == doctest::Approx(0.1 * 1 + 0.2 * 2 + 0.3 * 3 + 0.4 * 4));
    CHECK(rebuilt[1] == doctest::Approx(0.1 * 10 + 0.2 * 20 + 0.3 * 30 + 0.4 * 40));
    CHECK(error[0] == doctest::Approx(0.1 * 0.1 + 0.2 * 0.2 + 0.3 * 0.3 + 0.4 * 0.4));
    CHECK(rebuilt[2] == doctest::Approx(0.25 * 4 + 0.75 * 2));
    CHECK(error[3] == doctest::Approx(0.25 * 4 + 0.75 * 2));
    CHECK(rebuilt[4] == 0.0f);
    CHECK(rebuilt[5] == 0.0f);
    CHECK(error[4] == 0.0f);

    for (float bad : {4.0f, -1.0f}) {
        set_entry(&lookup[0], {0, bad}, {0.5f, 0.5f});
        try {
            objectspace::rebuild_from_points(lookup.data(), 1, values.data(), sigma.data(), channels, 4,
                                             "shot.0007.exr", rebuilt.data(), error.data());
            FAIL("no error for point id " << bad);
        } catch (const Error& error_thrown) {
            CHECK(std::string(error_thrown.what()).find("shot.0007.exr") != std::string::npos);
        }
    }
}

TEST_CASE("point rebuild: a static camera's pixels rebuilt from the points' positions see those positions")
{
    const scene::Scene room = scene::make_builtin_scene("static", 1);
    const render::SurfacePoints points(room, 0.05, 1 << 24);
    render::RenderOptions options;
    options.width = 48;
    options.height = 36;
    options.spp = 1; // one hit per pixel: its lookup is the lattice cell around that hit
    render::FrameAovs frame;
    render::render_frame(room, 1, options, nullptr, frame, Progress::silent(), &points);
    render::PointBake bake;
    render::bake_points(room, 1, points, options, bake, Progress::silent());

    const std::size_t pixels = static_cast<std::size_t>(options.width) * options.height;
    std::vector<float> rebuilt(pixels * 3), unused_sigma(pixels * 3);
    const std::vector<float> zero_sigma(bake.position.pixels.size(), 0.0f);
    objectspace::rebuild_from_points(frame.point_lookup.pixels.data(), pixels, bake.position.pixels.data(),
                                     zero_sigma.data(), 3, points.count(), "frame", rebuilt.data(),
                                     unused_sigma.data());
    int compared = 0;
    double worst = 0;
    for (std::size_t p = 0; p < pixels; ++p) {
        if (!(frame.point_lookup.pixels[p * kLookupChannels + kLookupPoints] > 0))
            continue; // no sample saw any albedo (a light, or nothing)
        ++compared;
        for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(static_cast<double>(rebuilt[p * 3 + c]) - frame.position.pixels[p * 3 + c]));
    }
    MESSAGE(compared << " pixels, largest distance between the rebuilt and the seen position " << worst << " m");
    CHECK(compared > static_cast<int>(pixels) / 2);
    // The lattice interpolates positions exactly; the points sit 1e-3 of the way to
    // their triangle's centroid (point_bake.cpp), a few millimetres on the room's walls.
    CHECK(worst < 0.01);
}
