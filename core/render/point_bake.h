// Baking the indirect light at the surface points of object-space denoising
// (surface_points.h): per frame and point, `spp` paths start on the point (from
// the front side of its triangle, albedo 1) and the light that arrives after two
// or more bounces is averaged, as DiffInd holds it for a pixel. Points are laid
// out in an image, kPointImageWidth per row in id order, so that the points ×
// frames matrix goes through the denoiser's EXR reader and engine unchanged.
// Like render_frame, every value depends only on (seed, frame, point, sample).
#pragma once

#include "core/common/progress.h"
#include "core/render/aov.h"
#include "core/render/render.h"
#include "core/render/surface_points.h"
#include "core/scene/scene.h"

#include <cstdint>

namespace modestack::render {

/// Points per row of a point image.
inline constexpr int kPointImageWidth = 1024;

/// Width × height of the image holding `count` points (the last row padded with zeros).
void point_image_size(std::int64_t count, int& width, int& height);

/// One frame's bake.
struct PointBake {
    AovImage indirect; ///< DiffInd at each point, RGB
    AovImage variance; ///< DiffIndVar: variance of each DiffInd value (0 at 1 spp)
    AovImage position; ///< Position: the point's world position in this frame
    AovImage normal;   ///< Normal: its triangle's unit front normal in this frame
    RenderStats stats;
};

/// Rows of the point image processed per progress unit.
inline constexpr int kBakeRowsPerStep = 4;

/// Number of progress units bake_points() advances by for `points`.
int bake_step_count(const SurfacePoints& points);

/// Bakes frame `frame` of `scene` (which must have the points' topology) with
/// options.spp samples per point. Checks cancel_requested() like render_frame.
void bake_points(const scene::Scene& scene, int frame, const SurfacePoints& points, const RenderOptions& options,
                 PointBake& out, Progress& progress);

} // namespace modestack::render
