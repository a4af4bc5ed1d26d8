// One frame of `modestack refine` on plain buffers ([0093]–[0095]): score the
// denoised indirect layer by its sigma, select the unsure pixels, feather the
// selection, re-render every pixel with a non-zero weight at high spp with the
// path tracer (same scene, frame and camera; the renderer's mask mode), and blend
// the new values and their noise into the layer. The two halves around the
// render are functions of their own, the one place of each rule, so that
// `refine --masks-only` (choose, let another renderer render) and
// `refine --blend` (blend what it rendered) do exactly what refine_frame does.
// The app reads and writes the files around it; tests call it directly on
// in-memory frames.
#pragma once

#include "core/common/progress.h"
#include "core/refine/feather.h"
#include "core/refine/selection.h"
#include "core/render/render.h"
#include "core/scene/scene.h"

#include <cstdint>

namespace modestack::refine {

/// What a pixel's score is (selection.h).
enum class RefineScore {
    RelativeError, ///< sigma / sqrt(value² + floor²), the largest over R, G, B
    Gain,          ///< the relMSE a re-render at render.spp removes
};

/// Every setting of a refine run except the selection threshold.
struct RefineSettings {
    float dark_floor = kDefaultDarkFloor; ///< see selection.h
    FeatherOptions feather;
    render::RenderOptions render; ///< size, spp (high, e.g. 256), seed, depth of the re-render
    RefineScore score = RefineScore::RelativeError;
    int input_spp = 0; ///< Gain: the spp of the denoised frames' input (their variance's)
};

/// Writes the score of every one of `pixels` pixels into `scores`, as
/// settings.score says, from the denoised `value` and `sigma` and (for Gain)
/// the input's variance of the mean `variance` (pixels·3 floats each).
void refine_scores(const RefineSettings& settings, const float* value, const float* sigma,
                   const float* variance, std::size_t pixels, float* scores);

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

/// The pixel-choice rule of refine: scores `value` and `sigma` (width·height·3
/// floats, interleaved, y = 0 at the top; `variance` too for RefineScore::Gain,
/// else it may be null) as refine_scores does, selects the pixels with a score ≥
/// `threshold` (selection.h; +infinity selects none), drops lone ones, and
/// writes the feathered blend weight of every pixel into `weights`
/// (width·height; > 0 = to be re-rendered). Fills the report's pixels,
/// selected_pixels, rendered_pixels and estimated_before (= estimated_after).
FrameRefineReport choose_refine_pixels(int width, int height, float threshold, const RefineSettings& settings,
                                       const float* value, const float* sigma, const float* variance,
                                       float* weights);

/// The blend of refine: puts re-rendered values (`rendered`, and the renderer's
/// `rendered_variance` of them, width·height·3 like `value`) into `value` and
/// `sigma` by `weights` (blend.h; weight 0 leaves a pixel bit for bit) and sets
/// report.estimated_after. `report.pixels` must be width·height.
void blend_refined_frame(const float* weights, const float* rendered, const float* rendered_variance,
                         float dark_floor, float* value, float* sigma, FrameRefineReport& report);

/// Refines frame `frame` of `scene` in place. `value` and `sigma` hold the
/// denoised DiffInd RGB and its sigma, `variance` the input's DiffIndVar (for
/// RefineScore::Gain; else it may be null) (width·height·3 floats, interleaved,
/// y = 0 at the top, size from settings.render); `weights` (width·height) receives
/// the blend weight of every pixel (0 = untouched, bit for bit). Pixels with a
/// score ≥ `threshold` (selection.h) are selected, lone ones dropped; +infinity selects none and then
/// nothing is rendered. Calls progress.advance() once per render tile
/// (render::tile_count) whether or not anything is rendered. Throws what
/// render_frame throws (bad options, cancellation).
FrameRefineReport refine_frame(const scene::Scene& scene, int frame, float threshold,
                               const RefineSettings& settings, float* value, float* sigma,
                               const float* variance, float* weights, Progress& progress);

} // namespace modestack::refine
