// Denoising the points × frames matrix (see point_denoise.h).
#include "core/objectspace/point_denoise.h"

#include "core/objectspace/leverage.h"

#include <chrono>
#include <cstddef>
#include <vector>

namespace modestack::objectspace {

PointDenoise denoise_points(denoise::FrameSource& points, denoise::Settings settings, const SurfaceSamples& samples,
                            SurfaceFilterOptions filter, Progress& progress)
{
    const denoise::ShotShape shape = points.shape();
    // Neighbours in a point image are not neighbours on the surfaces: nothing spatial.
    settings.mode_filter.enabled = false;
    settings.feature_guide.kinds.clear();
    settings.rank_map.enabled = false;
    settings.sigma_radius = 0;
    KeepingSource noisy(points); // every row is read: pass 1 needs them all for the statistics
    PointDenoise result{PointStore(shape), {}, {}, false};
    result.report = denoise::run_denoise(noisy, result.points, settings, progress);
    if (samples.count() == 0 || !(samples.spacing > 0))
        return result;

    // Sigma (and the filter) over the surfaces: the engine's sigma pooled over a
    // point image's rows, which are not surface neighbours.
    const std::vector<double> leverages = frame_leverages(result.report.temporal_modes, shape.frames);
    std::vector<SurfaceFrame> frames;
    for (int t = 0; t < shape.frames; ++t)
        frames.push_back({noisy.frame(t), result.points.values(t), result.points.sigma(t),
                          leverages[static_cast<std::size_t>(t)]});
    filter.kept_modes = result.report.rank_decision.kept_modes;
    progress.begin("surface filter and sigma", 1);
    const auto start = std::chrono::steady_clock::now();
    result.filter = filter_surfaces(samples, filter, shape.channels, result.report.rebuild_weights, frames);
    result.filter.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.end();
    result.over_surfaces = true;
    return result;
}

} // namespace modestack::objectspace
