// Denoising the points × frames matrix (see point_denoise.h).
#include "core/objectspace/point_denoise.h"

#include "core/common/error.h"
#include "core/objectspace/leverage.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

namespace modestack::objectspace {

struct PointDenoise::Held {
    Held(denoise::FrameSource& points, bool keep_input, bool keep_sigma)
        : source(points), shape(points.shape()), store(shape, keep_sigma)
    {
        if (keep_input)
            kept.emplace(points);
    }
    denoise::FrameSource& source;
    denoise::ShotShape shape;
    std::optional<KeepingSource> kept; // the engine's input, when it fits
    PointStore store;
    SurfaceShot shot;
    std::optional<SurfaceFilter> filter;
    mutable tbb::enumerable_thread_specific<std::vector<float>> noisy_of_worker;

    std::int64_t frame_values() const
    {
        return static_cast<std::int64_t>(shape.width) * shape.height * shape.channels;
    }
    void read_noisy(int t, float* destination) const
    {
        if (kept) {
            const float* frame = kept->frame(t);
            std::copy(frame, frame + frame_values(), destination);
        } else {
            source.read_rows(t, 0, shape.height, destination, nullptr);
        }
    }
};

PointDenoise::PointDenoise() = default;
PointDenoise::PointDenoise(PointDenoise&&) noexcept = default;
PointDenoise::~PointDenoise() = default;

std::int64_t PointDenoise::frame_values() const
{
    return held->frame_values();
}

void PointDenoise::frame(int t, float* values, float* sigma) const
{
    const Held& points = *held;
    const std::size_t all = static_cast<std::size_t>(points.frame_values());
    const float* rebuilt = points.store.values(t);
    std::copy(rebuilt, rebuilt + all, values);
    if (!points.filter) { // the engine's values and sigma over the point image
        std::copy(points.store.sigma(t), points.store.sigma(t) + all, sigma);
        return;
    }
    // Padding points past the samples' keep their rebuilt value and no sigma.
    std::fill(sigma, sigma + all, 0.0f);
    const float* noisy = nullptr;
    if (points.kept) {
        noisy = points.kept->frame(t); // no copy
    } else {
        std::vector<float>& buffer = points.noisy_of_worker.local();
        buffer.resize(all);
        points.read_noisy(t, buffer.data());
        noisy = buffer.data();
    }
    points.filter->frame(t, noisy, values, sigma);
}

PointDenoise denoise_points(denoise::FrameSource& points, denoise::Settings settings, const SurfaceSamples& samples,
                            SurfaceFilterOptions filter, Progress& progress)
{
    const denoise::ShotShape shape = points.shape();
    // Neighbours in a point image are not neighbours on the surfaces: nothing spatial.
    settings.mode_filter.enabled = false;
    settings.feature_guide.kinds.clear();
    settings.rank_map.enabled = false;
    settings.sigma_radius = 0;
    // Nor a frame noise measured along a point image's rows (its horizontal
    // high-pass is of unrelated points), which the surface filter's noise
    // model would not count either.
    settings.measured_frame_noise = false;
    const bool over_surfaces = samples.count() > 0 && samples.spacing > 0;
    const std::int64_t matrix_bytes = static_cast<std::int64_t>(shape.width) * shape.height * shape.channels *
                                      shape.frames * static_cast<std::int64_t>(sizeof(float));
    // Held after the engine: the rebuild (and the engine's sigma), and the
    // surface filter: its window's lists, made now to be counted, and its
    // arrays for N up to kReservedModes (N is known only after the engine;
    // beyond it, the input's copy is given up first).
    constexpr int kReservedModes = 2;
    std::optional<SurfaceNeighbours> window;
    std::int64_t kept_bytes = matrix_bytes * (over_surfaces ? 1 : 2);
    if (over_surfaces) {
        window.emplace(SurfaceFilter::window_neighbours(samples, filter));
        kept_bytes +=
            window->bytes() + SurfaceFilter::state_bytes(samples.count(), shape.channels, kReservedModes);
    }
    if (kept_bytes >= settings.max_memory_bytes)
        throw usage_error(
            fmt::format("--max-memory leaves {} MiB for the points, too little for object space: the "
                        "rebuilt points and their surface filter alone hold {} MiB",
                        settings.max_memory_bytes >> 20, (kept_bytes >> 20) + 1));
    // The input too when the engine is still left as much as one matrix: its
    // bands are then not much narrower than without the copy.
    const bool keep_input = over_surfaces && kept_bytes + 2 * matrix_bytes <= settings.max_memory_bytes;
    const std::int64_t budget = settings.max_memory_bytes;
    settings.max_memory_bytes -= kept_bytes + (keep_input ? matrix_bytes : 0);

    PointDenoise result;
    result.held = std::make_unique<PointDenoise::Held>(points, keep_input, !over_surfaces);
    PointDenoise::Held& held = *result.held;
    result.input_kept = keep_input;
    denoise::FrameSource& engine_input = keep_input ? static_cast<denoise::FrameSource&>(*held.kept) : points;
    result.report = denoise::run_denoise(engine_input, held.store, settings, progress);
    if (!over_surfaces)
        return result;

    // Sigma (and the filter) over the surfaces: the engine's sigma pooled over a
    // point image's rows, which are not surface neighbours.
    held.shot.read_noisy = [&held](int t, float* destination) { held.read_noisy(t, destination); };
    for (int t = 0; t < shape.frames; ++t)
        held.shot.rebuilt.push_back(held.store.values(t));
    held.shot.leverages = frame_leverages(result.report.temporal_modes, shape.frames);
    held.shot.channels = shape.channels;
    held.shot.frame_values = held.frame_values();
    filter.kept_modes = result.report.rank_decision.kept_modes;
    // More modes than reserved for: give the input copy's memory to the filter.
    const std::int64_t filter_bytes =
        window->bytes() + SurfaceFilter::state_bytes(samples.count(), shape.channels,
                                                     static_cast<int>(result.report.rebuild_weights.size()));
    if (held.kept && matrix_bytes * 2 + filter_bytes > budget) {
        held.kept.reset();
        result.input_kept = false;
    }
    progress.begin("surface filter and sigma", 1);
    const auto start = std::chrono::steady_clock::now();
    held.filter.emplace(samples, filter, result.report.rebuild_weights, held.shot, std::move(*window));
    result.filter = held.filter->choice();
    result.filter.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.end();
    result.over_surfaces = true;
    return result;
}

} // namespace modestack::objectspace
