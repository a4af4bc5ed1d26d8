// One refined frame with the real path tracer: fully weighted pixels hold exactly
// what a full high-spp render gives there (the mask render is the full render on
// its pixels), unweighted pixels keep their bits, the ring between is the blend,
// sigma becomes the renderer's noise, and the result does not depend on threads.
#include "core/refine/refine_frame.h"

#include "core/scene/builtin_scenes.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace modestack;
using namespace modestack::refine;

namespace {

constexpr int kWidth = 32, kHeight = 24, kFrame = 33;

render::FrameAovs render_full(int spp, std::uint64_t seed)
{
    render::RenderOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.spp = spp;
    options.seed = seed;
    render::FrameAovs aovs;
    render::render_frame(scene::make_builtin_scene("switch", kFrame), kFrame, options, nullptr, aovs,
                         Progress::silent());
    return aovs;
}

// A denoised-looking frame: the 4-spp indirect light, with a confident sigma
// except in a small block where sigma is as large as the value.
struct FakeDenoised {
    std::vector<float> value, sigma;
};

FakeDenoised fake_denoised()
{
    FakeDenoised frame;
    frame.value = render_full(4, 1).diffuse_indirect.pixels;
    frame.sigma.assign(frame.value.size(), 1e-4f);
    for (int y = 10; y < 14; ++y)
        for (int x = 12; x < 18; ++x)
            for (int c = 0; c < 3; ++c)
                frame.sigma[(static_cast<size_t>(y) * kWidth + x) * 3 + c] = 1.0f;
    return frame;
}

RefineSettings settings_for_test()
{
    RefineSettings settings;
    settings.render.width = kWidth;
    settings.render.height = kHeight;
    settings.render.spp = 32;
    settings.render.seed = 2;
    settings.feather.dilation = 1;
    settings.feather.feather = 2;
    return settings;
}

} // namespace

TEST_CASE("refine_frame blends the high-spp render into the unsure block by its inverse-variance share, "
          "feathered at "
          "its border")
{
    FakeDenoised before = fake_denoised(), after = before;
    RefineSettings settings = settings_for_test();
    std::vector<float> weights(kWidth * kHeight);
    scene::Scene scene = scene::make_builtin_scene("switch", kFrame);
    FrameRefineReport report = refine_frame(scene, kFrame, 0.5f, settings, after.value.data(),
                                            after.sigma.data(), nullptr, weights.data(), Progress::silent());
    render::FrameAovs reference = render_full(32, 2);
    CHECK(report.selected_pixels == 24);
    int full = 0, partial = 0, untouched = 0;
    for (size_t p = 0; p < weights.size(); ++p) {
        float w = weights[p];
        // The render's share: the feather times s / (s + r), the channel means of the variances (blend.h).
        double s = 0, r = 0;
        for (int c = 0; c < 3; ++c) {
            s += double(before.sigma[p * 3 + c]) * before.sigma[p * 3 + c];
            r += std::max(0.0f, reference.indirect_variance.pixels[p * 3 + c]);
        }
        const double share = s + r > 0 ? w * s / (s + r) : w;
        if (before.sigma[p * 3] == 1.0f)
            CHECK(share >
                  0.5); // the unsure block is mostly the render; its confident ring stays mostly itself
        for (int c = 0; c < 3; ++c) {
            size_t i = p * 3 + c;
            if (w == 0.0f) {
                CHECK(std::memcmp(&after.value[i], &before.value[i], sizeof(float)) == 0);
                CHECK(after.sigma[i] == before.sigma[i]);
            } else {
                const double variance = std::max(0.0f, reference.indirect_variance.pixels[i]);
                CHECK(after.value[i] == doctest::Approx(share * reference.diffuse_indirect.pixels[i] +
                                                        (1 - share) * before.value[i]));
                CHECK(after.sigma[i] == doctest::Approx(std::sqrt(share * share * variance +
                                                                  (1 - share) * (1 - share) *
                                                                      before.sigma[i] * before.sigma[i])));
            }
        }
        (w == 0.0f ? untouched : w == 1.0f ? full : partial) += 1;
    }
    CHECK(full >= 24);
    CHECK(partial > 0);
    CHECK(report.rendered_pixels == full + partial);
    CHECK(report.estimated_after < report.estimated_before);
}

TEST_CASE("refine_frame with nothing above the threshold renders nothing and changes no bit")
{
    FakeDenoised before = fake_denoised(), after = before;
    std::vector<float> weights(kWidth * kHeight, -1.0f);
    FrameRefineReport report =
        refine_frame(scene::make_builtin_scene("switch", kFrame), kFrame,
                     std::numeric_limits<float>::infinity(), settings_for_test(), after.value.data(),
                     after.sigma.data(), nullptr, weights.data(), Progress::silent());
    CHECK(report.rendered_pixels == 0);
    CHECK(report.stats.paths == 0);
    CHECK(std::memcmp(after.value.data(), before.value.data(), before.value.size() * sizeof(float)) == 0);
    CHECK(std::memcmp(after.sigma.data(), before.sigma.data(), before.sigma.size() * sizeof(float)) == 0);
    CHECK(std::all_of(weights.begin(), weights.end(), [](float w) { return w == 0.0f; }));
}

TEST_CASE("refine_frame gives the same bits for one and two threads")
{
    FakeDenoised one = fake_denoised(), two = one;
    std::vector<float> weights_one(kWidth * kHeight), weights_two(kWidth * kHeight);
    scene::Scene scene = scene::make_builtin_scene("switch", kFrame);
    tbb::task_arena(1).execute([&] {
        refine_frame(scene, kFrame, 0.5f, settings_for_test(), one.value.data(), one.sigma.data(), nullptr,
                     weights_one.data(), Progress::silent());
    });
    tbb::task_arena(2).execute([&] {
        refine_frame(scene, kFrame, 0.5f, settings_for_test(), two.value.data(), two.sigma.data(), nullptr,
                     weights_two.data(), Progress::silent());
    });
    CHECK(std::memcmp(one.value.data(), two.value.data(), one.value.size() * sizeof(float)) == 0);
    CHECK(std::memcmp(one.sigma.data(), two.sigma.data(), one.sigma.size() * sizeof(float)) == 0);
    CHECK(weights_one == weights_two);
}
