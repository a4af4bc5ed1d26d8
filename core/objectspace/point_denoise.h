// Object-space denoising of the points × frames matrix that `render --points`
// baked (core/render/point_bake.h), without files: the same low-rank engine,
// rank rule and confidence as images run on the point image, with everything
// spatial left out (neighbours in a point image are not neighbours on the
// surfaces: no mode filter, feature guide, rank map or sigma pooling), then the
// surface filter (surface_filter.h) takes the mode filter's place and sigma is
// pooled over the points' positions and normals. The app reads the files and
// rebuilds each frame from the result (point_rebuild.h).
#pragma once

#include "core/common/progress.h"
#include "core/denoise/engine.h"
#include "core/denoise/frame_stream.h"
#include "core/objectspace/point_store.h"
#include "core/objectspace/surface_filter.h"
#include "core/objectspace/surface_samples.h"

#include <cstdint>
#include <memory>

namespace modestack::objectspace {

/// What denoising the points gave: every frame's points, made on demand.
class PointDenoise {
public:
    denoise::Report report;      ///< the engine's, on the point image
    SurfaceFilterChoice filter;  ///< what the surface filter chose (width 0: none)
    bool over_surfaces = false;  ///< whether sigma and the filter went over the surfaces
    bool input_kept = false;     ///< the engine's input was kept in memory (else read again per frame)

    /// Frame t's point values and sigma, [point][channel] over the whole point
    /// image (frame_values() floats each). May be called concurrently for
    /// different frames; reads the points' frame again unless input_kept.
    void frame(int t, float* values, float* sigma) const;
    std::int64_t frame_values() const;

    PointDenoise();
    PointDenoise(PointDenoise&&) noexcept;
    ~PointDenoise();
    struct Held; ///< the kept matrices and the filter, where frame() finds them
    std::unique_ptr<Held> held;
};

/// Denoises `points` (a point image per frame) with `settings` less their
/// spatial parts. When `samples` has positions, normals and a spacing, sigma is
/// then pooled over the surfaces and the points are filtered as `filter` says
/// (its rank is set here to the engine's N); otherwise the engine's sigma over
/// the point image stays and nothing is filtered. The rebuild and the surface
/// filter's state are kept in memory, and the input too when the engine is
/// then still left one matrix's worth of settings.max_memory_bytes; the engine
/// gets the rest of the budget. `points` must outlive the result (frame() reads
/// it again). Throws a usage error when the budget cannot hold the rebuild and
/// the filter; the engine's band plan refuses a rest too small for one band in
/// its own words.
PointDenoise denoise_points(denoise::FrameSource& points, denoise::Settings settings, const SurfaceSamples& samples,
                            SurfaceFilterOptions filter, Progress& progress);

} // namespace modestack::objectspace
