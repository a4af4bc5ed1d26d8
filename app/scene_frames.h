// The one rule for frames a scene does not have: render's --frames and refine's
// denoised frames must lie in the scene's frame range, and both say so in the
// words core/scene uses for a single frame.
#pragma once

#include <string>

namespace modestack::app {

/// "frame 49 is outside scene 'orbit' (frames 1-48)".
std::string frame_outside_scene(int frame, const std::string& scene, int first_frame, int last_frame);

}  // namespace modestack::app
