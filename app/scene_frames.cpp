#include "app/scene_frames.h"

#include <fmt/format.h>

namespace modestack::app {

std::string frame_outside_scene(int frame, const std::string& scene, int first_frame, int last_frame)
{
    return fmt::format("frame {} is outside scene '{}' (frames {}-{})", frame, scene, first_frame, last_frame);
}

}  // namespace modestack::app
