// Built-in scenes and glTF files behind one interface (see scene_source.h).
#include "app/scene_source.h"

#include "core/common/error.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/gltf_loader.h"

namespace modestack::app {

SceneSource::SceneSource(const std::string& scene, double fps) : m_name(scene)
{
    if (scene::is_gltf_path(scene)) {
        m_gltf = std::make_shared<const scene::GltfScene>(scene::load_gltf(scene));
        m_fps = scene::gltf_fps(*m_gltf, fps);
        m_first_frame = 1;
        m_last_frame = scene::gltf_last_frame(*m_gltf, m_fps);
        return;
    }
    if (fps > 0)
        throw usage_error("--fps applies to glTF scenes (--scene FILE.gltf|FILE.glb) only");
    for (const auto& info : scene::builtin_scenes())
        if (info.name == scene) {
            m_first_frame = info.first_frame;
            m_last_frame = info.last_frame;
            return;
        }
    scene::make_builtin_scene(scene, 1); // throws the error that lists the scenes
}

std::vector<std::string> SceneSource::notices() const
{
    return m_gltf ? m_gltf->notices.messages() : std::vector<std::string>{};
}

scene::Scene SceneSource::at(int frame) const
{
    if (m_gltf)
        return scene::gltf_scene_at(*m_gltf, scene::gltf_frame_time(frame, m_fps));
    return scene::make_builtin_scene(m_name, frame);
}

} // namespace modestack::app
