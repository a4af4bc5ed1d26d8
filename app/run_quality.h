// The measurements of `modestack run --reference-spp` (docs/design.md, "How
// quality is measured"): from the per-frame relMSE of the noisy, denoised and refined results
// against the reference, and the two renders' times, the JSON block with relMSE,
// equivalent spp and the equal-quality speed-up of each, for the indirect layer and
// the beauty.
#pragma once

#include "core/scene/builtin_scenes.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace modestack::app {

/// One render of the whole shot.
struct RenderTiming {
    int spp = 0;
    double seconds = 0;  ///< render time of all frames
};

/// `errors[layer][version][frame]`: layer 0 DiffInd, 1 beauty; version 0 noisy,
/// 1 denoised, 2 refined. `seconds` holds run's stage times ("render", "denoise",
/// "total"). The scene's highlight frames (switch: the crossing), when it has
/// any, are also reported on their own.
nlohmann::ordered_json quality_summary(const scene::FrameSpan& highlight_frames, const std::vector<int>& frames,
                                       const std::vector<std::vector<std::vector<double>>>& errors,
                                       const nlohmann::ordered_json& seconds, RenderTiming noisy,
                                       RenderTiming reference);

}  // namespace modestack::app
