#include "core/refine/refine_frame.h"

#include "core/refine/blend.h"

#include <chrono>
#include <vector>

namespace modestack::refine {

FrameRefineReport refine_frame(const scene::Scene& scene, int frame, float threshold,
                               const RefineSettings& settings, float* value, float* sigma, float* weights,
                               Progress& progress)
{
    const int width = settings.render.width, height = settings.render.height;
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    constexpr int kChannels = 3;
    FrameRefineReport report;
    report.pixels = static_cast<std::int64_t>(pixels);
    report.estimated_before = estimated_relative_mse(value, sigma, pixels, kChannels, settings.dark_floor);

    std::vector<float> scores(pixels);
    relative_error_scores(value, sigma, pixels, kChannels, settings.dark_floor, scores.data());
    std::vector<std::uint8_t> selection = select_pixels(scores.data(), pixels, threshold);
    drop_isolated_pixels(selection, width, height);
    feathered_weights(selection.data(), width, height, settings.feather, weights);
    std::vector<std::uint8_t> mask(pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
        report.selected_pixels += selection[p];
        mask[p] = weights[p] > 0 ? 1 : 0;
        report.rendered_pixels += mask[p];
    }
    if (report.rendered_pixels == 0) {
        progress.advance(render::tile_count(settings.render));
        report.estimated_after = report.estimated_before;
        return report;
    }
    auto start = std::chrono::steady_clock::now();
    render::FrameAovs aovs;
    render::render_frame(scene, frame, settings.render, mask.data(), aovs, progress);
    report.seconds_render = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.stats = aovs.stats;
    blend_refined(weights, pixels, kChannels, aovs.diffuse_indirect.pixels.data(),
                  aovs.indirect_variance.pixels.data(), value, sigma);
    report.estimated_after = estimated_relative_mse(value, sigma, pixels, kChannels, settings.dark_floor);
    return report;
}

} // namespace modestack::refine
