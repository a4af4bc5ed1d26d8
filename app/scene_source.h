// What `--scene` names: a built-in scene (by name) or a glTF 2.0 file (a name
// ending in .gltf or .glb), behind one interface that gives the frame range and
// builds the scene of any frame, so that the render path does not care which.
#pragma once

#include "core/scene/gltf_scene.h"
#include "core/scene/scene.h"

#include <memory>
#include <string>
#include <vector>

namespace modestack::app {

/// The scene of every frame of a shot.
class SceneSource {
public:
    /// Opens `scene`: a built-in scene name, or a glTF file loaded now. `fps` (> 0)
    /// maps glTF frames to time; 0 takes the file's or 24. Throws a usage error for
    /// an unknown name or --fps with a built-in scene, a bad-input error for a bad file.
    SceneSource(const std::string& scene, double fps);

    const std::string& name() const { return m_name; }
    bool is_gltf() const { return m_gltf != nullptr; }
    int first_frame() const { return m_first_frame; }
    int last_frame() const { return m_last_frame; }
    /// Frames per second of a glTF scene (0 for built-in scenes).
    double fps() const { return m_fps; }
    /// What the glTF file uses that is approximated or not rendered, one line each.
    std::vector<std::string> notices() const;
    /// The scene of frame `frame`.
    scene::Scene at(int frame) const;

private:
    std::string m_name;
    int m_first_frame = 1, m_last_frame = 1;
    double m_fps = 0;
    std::shared_ptr<const scene::GltfScene> m_gltf;
};

} // namespace modestack::app
