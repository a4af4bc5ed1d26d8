// One frame of `modestack refine` on plain buffers ([0093]–[0095]): score the
// denoised indirect layer by its sigma, select the unsure pixels, feather the
// selection, re-render every pixel with a non-zero weight at high spp with the
// path tracer (same scene, frame and camera; the renderer's mask mode), and blend
// the new values and their noise into the layer. The app reads and writes the
// files around it; tests call it directly on in-memory frames.
#pragma once

#include "core/common/progress.h"
#include "core/refine/feather.h"
#include "core/refine/selection.h"
#include "core/render/render.h"
#include "core/scene/scene.h"

#include <cstdint>

namespace modestack::refine {

/// Every setting of a refine run except the selection threshold.
struct RefineSettings {
    float dark_floor = kDefaultDarkFloor; ///< see selection.h
    FeatherOptions feather;
    render::RenderOptions render; ///< size, spp (high, e.g. 256), seed, depth of the re-render
};

/// What refine_frame() did to one frame.
struct FrameRefineReport {
    std::int64_t pixels = 0;          ///< width × height
    std::int64_t selected_pixels = 0; ///< score above the threshold, lone pixels dropped (before dilation)
    std::int64_t rendered_pixels = 0; ///< weight > 0: re-rendered and blended
    double seconds_render = 0;        ///< wall time of the re-render
    double estimated_before = 0;      ///< relMSE predicted by sigma before (blend.h)
    double estimated_after = 0;       ///< and after
    render::RenderStats stats;        ///< the re-render's paths and rays
};

/// Refines frame `frame` of `scene` in place. `value` and `sigma` hold the
/// denoised DiffInd RGB and its sigma (width·height·3 floats, interleaved,
/// y = 0 at the top, size from settings.render); `weights` (width·height) receives
/// the blend weight of every pixel (0 = untouched, bit for bit). Pixels with a
/// score ≥ `threshold` (selection.h) are selected, lone ones dropped; +infinity selects none and then
/// nothing is rendered. Calls progress.advance() once per render tile
/// (render::tile_count) whether or not anything is rendered. Throws what
/// render_frame throws (bad options, cancellation).
FrameRefineReport refine_frame(const scene::Scene& scene, int frame, float threshold,
                               const RefineSettings& settings, float* value, float* sigma, float* weights,
                               Progress& progress);

} // namespace modestack::refine
