// The path tracer's radiometry and promises: white furnace (closed room, albedo a,
// emission e → radiance e / (1 − a)), error falling as 1/spp, bit-identical frames
// for any thread count, masks, fixed seeds, the AOV identity
// Combined = DiffCol × (DiffDir + DiffInd) + Emit, and errors for bad options.
#include "core/common/error.h"
#include "core/render/render.h"
#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

using namespace modestack;
using render::FrameAovs;
using render::RenderOptions;

namespace {

FrameAovs render_small(const scene::Scene& scene, int frame, const RenderOptions& options,
                       const std::uint8_t* mask = nullptr)
{
    FrameAovs aovs;
    render::render_frame(scene, frame, options, mask, aovs, Progress::silent());
    return aovs;
}

RenderOptions small_options(int spp, std::uint64_t seed = 1)
{
    RenderOptions options;
    options.width = 32;
    options.height = 24;
    options.spp = spp;
    options.seed = seed;
    return options;
}

double mean_rgb(const render::AovImage& image)
{
    double sum = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c)
                sum += image.at(x, y)[c];
    return sum / (3.0 * image.width * image.height);
}

double relative_mse(const render::AovImage& image, const render::AovImage& reference)
{
    double sum = 0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        if (i % 4 == 3)
            continue; // alpha
        double r = reference.pixels[i], d = image.pixels[i] - r;
        sum += d * d / (r * r + 0.01);
    }
    return sum / (0.75 * static_cast<double>(image.pixels.size()));
}

bool same_bytes(const render::AovImage& a, const render::AovImage& b)
{
    return a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

bool same_bytes(const FrameAovs& a, const FrameAovs& b)
{
    auto layers_a = render::aov_layers(a), layers_b = render::aov_layers(b);
    for (std::size_t i = 0; i < layers_a.size(); ++i)
        if (!same_bytes(*layers_a[i].image, *layers_b[i].image))
            return false;
    return true;
}

} // namespace

TEST_CASE("tracer: white furnace gives radiance e / (1 - a)")
{
    const float albedo = 0.5f, emission = 0.5f;
    scene::Scene furnace = scene::make_furnace_scene(albedo, emission);
    RenderOptions options = small_options(64);
    options.max_depth = 64; // a^64: truncation far below the tolerance; roulette is unbiased
    FrameAovs aovs = render_small(furnace, 1, options);
    double radiance = mean_rgb(aovs.beauty);
    MESSAGE("furnace radiance (expected 1): " << radiance);
    CHECK(std::abs(radiance - emission / (1 - albedo)) < 0.02);
    // Every pixel too, not just the mean: no pixel is far off, and the typical
    // pixel is within a few percent at 64 spp.
    double squared_deviation = 0, worst_deviation = 0;
    for (std::size_t i = 0; i < aovs.beauty.pixels.size(); ++i) {
        double deviation = std::abs(aovs.beauty.pixels[i] - 1.0);
        if (i % 4 == 3)
            CHECK(aovs.beauty.pixels[i] == 1.0f); // alpha: closed room
        squared_deviation += deviation * deviation / aovs.beauty.pixels.size();
        worst_deviation = std::max(worst_deviation, deviation);
    }
    MESSAGE("furnace per-pixel RMS deviation " << std::sqrt(squared_deviation) << ", worst "
                                               << worst_deviation);
    CHECK(std::sqrt(squared_deviation) < 0.05);
    CHECK(worst_deviation < 0.35);
}

TEST_CASE("tracer: max_depth truncates the furnace series exactly where it says")
{
    // With at most k bounces the furnace sums e·(1 + a + ... + a^k). Roulette starts
    // after the third bounce, so k = 2 has no roulette noise at all.
    scene::Scene furnace = scene::make_furnace_scene(0.5f, 0.5f);
    for (int depth : {1, 2}) {
        RenderOptions options = small_options(16);
        options.max_depth = depth;
        double expected = 0.5 * (1 - std::pow(0.5, depth + 1)) / 0.5;
        double radiance = mean_rgb(render_small(furnace, 1, options).beauty);
        CHECK(radiance == doctest::Approx(expected).epsilon(0.01));
    }
}

TEST_CASE("tracer: relMSE falls as 1/spp")
{
    scene::Scene room = scene::make_builtin_scene("static", 1);
    FrameAovs reference = render_small(room, 1, small_options(2048, 99));
    std::vector<double> log_spp, log_error;
    for (int spp = 4; spp <= 64; spp *= 2) {
        // Average over two seeds: a steadier estimate of the expected error.
        double error =
            0.5 * (relative_mse(render_small(room, 1, small_options(spp, 1)).beauty, reference.beauty) +
                   relative_mse(render_small(room, 1, small_options(spp, 2)).beauty, reference.beauty));
        log_spp.push_back(std::log(spp));
        log_error.push_back(std::log(error));
        MESSAGE("spp " << spp << ": relMSE " << error);
    }
    double mean_x = 0, mean_y = 0;
    for (std::size_t i = 0; i < log_spp.size(); ++i) {
        mean_x += log_spp[i] / log_spp.size();
        mean_y += log_error[i] / log_spp.size();
    }
    double covariance = 0, variance = 0;
    for (std::size_t i = 0; i < log_spp.size(); ++i) {
        covariance += (log_spp[i] - mean_x) * (log_error[i] - mean_y);
        variance += (log_spp[i] - mean_x) * (log_spp[i] - mean_x);
    }
    double slope = covariance / variance;
    MESSAGE("log-log slope of relMSE against spp: " << slope);
    CHECK(std::abs(slope + 1.0) < 0.15);
}

TEST_CASE("tracer: frames are byte-identical for 1 and 2 threads")
{
    scene::Scene room = scene::make_builtin_scene("spin", 7);
    RenderOptions options = small_options(4);
    options.width = 45; // partial tiles on both axes
    options.height = 37;
    FrameAovs one, two;
    tbb::task_arena(1).execute([&] { one = render_small(room, 7, options); });
    tbb::task_arena(2).execute([&] { two = render_small(room, 7, options); });
    CHECK(same_bytes(one, two));
    CHECK(one.stats.paths == two.stats.paths);
    CHECK(one.stats.rays == two.stats.rays);
    CHECK(one.stats.paths == 45 * 37 * 4);
}

TEST_CASE("tracer: a mask renders exactly the full render's values on its pixels")
{
    scene::Scene room = scene::make_builtin_scene("switch", 33);
    RenderOptions options = small_options(4);
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(options.width) * options.height, 0);
    for (int y = 0; y < options.height; ++y)
        for (int x = 0; x < options.width; ++x)
            mask[static_cast<std::size_t>(y) * options.width + x] =
                ((x * 7 + y * 13) % 5 == 0) || (x > 20 && y < 6);
    FrameAovs full = render_small(room, 33, options), masked = render_small(room, 33, options, mask.data());
    int rendered_pixels = 0;
    for (const render::AovLayer& layer : render::aov_layers(masked)) {
        const render::AovImage* full_image = nullptr;
        for (const render::AovLayer& candidate : render::aov_layers(full))
            if (candidate.name == layer.name)
                full_image = candidate.image;
        REQUIRE(full_image != nullptr);
        for (int y = 0; y < options.height; ++y)
            for (int x = 0; x < options.width; ++x)
                for (int c = 0; c < layer.image->channels; ++c) {
                    bool on = mask[static_cast<std::size_t>(y) * options.width + x] != 0;
                    float expected = on ? full_image->at(x, y)[c] : 0.0f;
                    if (layer.image->at(x, y)[c] != expected) {
                        FAIL_CHECK(layer.name << " differs at " << x << "," << y);
                        return;
                    }
                }
    }
    for (std::uint8_t m : mask)
        rendered_pixels += m != 0;
    CHECK(masked.stats.paths == static_cast<long long>(rendered_pixels) * options.spp);
    CHECK(rendered_pixels > 0);
}

TEST_CASE("tracer: fixed seed repeats the noise of a static scene and default seeds do not")
{
    scene::Scene frame_1 = scene::make_builtin_scene("static", 1),
                 frame_2 = scene::make_builtin_scene("static", 2);
    RenderOptions options = small_options(2);
    options.fixed_seed = true;
    CHECK(same_bytes(render_small(frame_1, 1, options).beauty, render_small(frame_2, 2, options).beauty));
    options.fixed_seed = false;
    FrameAovs a = render_small(frame_1, 1, options), b = render_small(frame_2, 2, options);
    int differing = 0;
    for (std::size_t i = 0; i < a.beauty.pixels.size(); i += 4)
        differing += a.beauty.pixels[i] != b.beauty.pixels[i];
    CHECK(differing > static_cast<int>(0.9 * a.beauty.pixels.size() / 4));
}

TEST_CASE("tracer: Combined = DiffCol x (DiffDir + DiffInd) + Emit per pixel")
{
    for (const char* name : {"static", "orbit"}) {
        FrameAovs aovs = render_small(scene::make_builtin_scene(name, 10), 10, small_options(8));
        double worst = 0;
        for (int y = 0; y < aovs.beauty.height; ++y)
            for (int x = 0; x < aovs.beauty.width; ++x)
                for (int c = 0; c < 3; ++c) {
                    double rebuilt = aovs.albedo.at(x, y)[c] * (aovs.diffuse_direct.at(x, y)[c] +
                                                                aovs.diffuse_indirect.at(x, y)[c]) +
                                     aovs.emission.at(x, y)[c];
                    double beauty = aovs.beauty.at(x, y)[c];
                    worst = std::max(worst, std::abs(rebuilt - beauty) / std::max(std::abs(beauty), 1e-3));
                }
        CHECK(worst < 1e-4);
    }
}

TEST_CASE("tracer: DiffIndVar predicts the spread of DiffInd between seeds")
{
    // The variance layer estimates the variance of the pixel mean from one render.
    // Stratified sampling can only make the real spread smaller than this i.i.d.
    // estimate, so the ratio real / predicted lies in (0, ~1].
    scene::Scene room = scene::make_builtin_scene("static", 1);
    const int seeds = 12;
    std::vector<FrameAovs> renders;
    for (int seed = 0; seed < seeds; ++seed)
        renders.push_back(render_small(room, 1, small_options(4, 100 + seed)));
    double predicted = 0, observed = 0;
    std::size_t count = renders[0].diffuse_indirect.pixels.size();
    for (std::size_t i = 0; i < count; ++i) {
        double mean = 0, predicted_here = 0;
        for (const FrameAovs& aovs : renders) {
            mean += aovs.diffuse_indirect.pixels[i] / seeds;
            predicted_here += aovs.indirect_variance.pixels[i] / seeds;
        }
        double spread = 0;
        for (const FrameAovs& aovs : renders)
            spread += std::pow(aovs.diffuse_indirect.pixels[i] - mean, 2) / (seeds - 1);
        predicted += predicted_here;
        observed += spread;
    }
    MESSAGE("observed / predicted DiffInd variance: " << observed / predicted);
    CHECK(observed / predicted > 0.5);
    CHECK(observed / predicted < 1.3);
}

TEST_CASE("tracer: bad options are usage errors")
{
    scene::Scene room = scene::make_builtin_scene("static", 1);
    auto kind_of = [&](RenderOptions options) {
        try {
            render_small(room, 1, options);
        } catch (const Error& error) {
            return error.kind();
        }
        return ErrorKind::Internal;
    };
    RenderOptions options = small_options(0);
    CHECK(kind_of(options) == ErrorKind::Usage);
    options = small_options(1);
    options.width = 0;
    options.height = 0;
    CHECK(kind_of(options) == ErrorKind::Usage);
    options = small_options(1);
    options.max_depth = 0;
    CHECK(kind_of(options) == ErrorKind::Usage);
    options = small_options(1);
    options.width = 1;
    options.height = 1; // 1×1 is fine
    FrameAovs one_pixel = render_small(room, 1, options);
    CHECK(one_pixel.rendered.pixels[0] == 1.0f);
    CHECK(std::isfinite(one_pixel.beauty.pixels[0]));
}
