#include "core/refine/refine_frame.h"

#include "core/common/error.h"
#include "core/refine/blend.h"

#include <chrono>
#include <vector>

namespace modestack::refine {
namespace {

constexpr int kChannels = 3; // the layer's R, G and B

} // namespace

void refine_scores(const RefineSettings& settings, const float* value, const float* sigma,
                   const float* variance, std::size_t pixels, float* scores)
{
    switch (settings.score) {
    case RefineScore::RelativeError:
        relative_error_scores(value, sigma, pixels, kChannels, settings.dark_floor, scores);
        return;
    case RefineScore::Gain:
        if (variance == nullptr || settings.input_spp < 1)
            throw internal_error("refine by gain without the input's variance and spp");
        refine_gains(value, sigma, variance, static_cast<double>(settings.input_spp) / settings.render.spp,
                     pixels, kChannels, settings.dark_floor, scores);
        return;
    }
}

FrameRefineReport choose_refine_pixels(int width, int height, float threshold, const RefineSettings& settings,
                                       const float* value, const float* sigma, const float* variance,
                                       float* weights)
{
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    FrameRefineReport report;
    report.pixels = static_cast<std::int64_t>(pixels);
    report.estimated_before = estimated_relative_mse(value, sigma, pixels, kChannels, settings.dark_floor);
    report.estimated_after = report.estimated_before;
    std::vector<float> scores(pixels);
    refine_scores(settings, value, sigma, variance, pixels, scores.data());
    std::vector<std::uint8_t> selection = select_pixels(scores.data(), pixels, threshold);
    drop_isolated_pixels(selection, width, height);
    feathered_weights(selection.data(), width, height, settings.feather, weights);
    for (std::size_t p = 0; p < pixels; ++p) {
        report.selected_pixels += selection[p];
        report.rendered_pixels += weights[p] > 0 ? 1 : 0;
    }
    return report;
}

void blend_refined_frame(const float* weights, const float* rendered, const float* rendered_variance,
                         float dark_floor, float* value, float* sigma, FrameRefineReport& report)
{
    const auto pixels = static_cast<std::size_t>(report.pixels);
    blend_refined(weights, pixels, kChannels, rendered, rendered_variance, value, sigma);
    report.estimated_after = estimated_relative_mse(value, sigma, pixels, kChannels, dark_floor);
}

FrameRefineReport refine_frame(const scene::Scene& scene, int frame, float threshold,
                               const RefineSettings& settings, float* value, float* sigma,
                               const float* variance, float* weights, Progress& progress)
{
    const int width = settings.render.width, height = settings.render.height;
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    FrameRefineReport report =
        choose_refine_pixels(width, height, threshold, settings, value, sigma, variance, weights);
    if (report.rendered_pixels == 0) {
        progress.advance(render::tile_count(settings.render));
        return report;
    }
    std::vector<std::uint8_t> mask(pixels);
    for (std::size_t p = 0; p < pixels; ++p)
        mask[p] = weights[p] > 0 ? 1 : 0;
    auto start = std::chrono::steady_clock::now();
    render::FrameAovs aovs;
    render::render_frame(scene, frame, settings.render, mask.data(), aovs, progress);
    report.seconds_render = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.stats = aovs.stats;
    blend_refined_frame(weights, aovs.diffuse_indirect.pixels.data(), aovs.indirect_variance.pixels.data(),
                        settings.dark_floor, value, sigma, report);
    return report;
}

} // namespace modestack::refine
