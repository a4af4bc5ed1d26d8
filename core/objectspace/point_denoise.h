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

namespace modestack::objectspace {

/// What denoising the points gave.
struct PointDenoise {
    PointStore points;           ///< every point's value and sigma in every frame
    denoise::Report report;      ///< the engine's, on the point image
    SurfaceFilterChoice filter;  ///< what the surface filter chose (width 0: none)
    bool over_surfaces = false;  ///< whether sigma and the filter went over the surfaces
};

/// Denoises `points` (a point image per frame) with `settings` less their
/// spatial parts. When `samples` has positions, normals and a spacing, sigma is
/// then pooled over the surfaces and the points are filtered as `filter` says
/// (its rank is set here to the engine's N); otherwise the engine's sigma over
/// the point image stays and nothing is filtered.
PointDenoise denoise_points(denoise::FrameSource& points, denoise::Settings settings, const SurfaceSamples& samples,
                            SurfaceFilterOptions filter, Progress& progress);

} // namespace modestack::objectspace
