// Rendering one frame of a scene into its AOV buffers: the entry point of the
// companion path tracer. The frame is cut into fixed 16×16 tiles traced in
// parallel with TBB; every pixel depends only on (seed, frame, pixel, sample), so
// the result is bit-identical for any thread count and tile order, and rendering
// only some pixels (a mask, for refine) gives those pixels exactly the values of a
// full render. See aov.h for the buffers and their suggested channel names.
#pragma once

#include "core/common/progress.h"
#include "core/render/aov.h"
#include "core/render/surface_points.h"
#include "core/scene/scene.h"

#include <cstdint>

namespace modestack::render {

/// How to render a frame.
struct RenderOptions {
    int width = 320;         ///< image width in pixels, ≥ 1
    int height = 240;        ///< image height in pixels, ≥ 1
    int spp = 4;             ///< samples per pixel, ≥ 1
    int max_depth = 8;       ///< maximum bounces, ≥ 1 (1 = direct light only)
    std::uint64_t seed = 1;  ///< seed of the sample hash
    bool fixed_seed = false; ///< same random numbers in every frame (frame left out of the hash)
};

/// Edge of the square tiles the frame is cut into, in pixels.
inline constexpr int kTileSize = 16;

/// Throws a usage error (e.g. "--spp must be at least 1") if `options` cannot be rendered.
void validate_render_options(const RenderOptions& options);

/// Number of tiles of a frame: render_frame() calls progress.advance(1) once per
/// tile, so a caller can begin() a phase of frames × tile_count(options) units.
int tile_count(const RenderOptions& options);

/// Renders frame `frame` (used for the sample hash only; `scene` is already that
/// frame's geometry) into `out`, which is resized to options.width × height.
/// `mask`: nullptr renders every pixel; otherwise width·height bytes, row-major,
/// y = 0 at the top, non-zero = render; other pixels are left zero in every layer
/// (their Rendered value is 0). Statistics go to out.stats. Checks
/// cancel_requested() before each tile and throws cancelled_error() (from
/// core/common/error.h) if the frame was left incomplete. Does not call
/// progress.begin()/end().
/// `points`: when given (object space), also fills out.point_lookup with the
/// surface points each pixel's samples saw; `scene` must have their topology.
/// Throws a usage error for bad options, a bad-input error for a broken scene.
void render_frame(const scene::Scene& scene, int frame, const RenderOptions& options,
                  const std::uint8_t* mask, FrameAovs& out, Progress& progress,
                  const SurfacePoints* points = nullptr);

} // namespace modestack::render
