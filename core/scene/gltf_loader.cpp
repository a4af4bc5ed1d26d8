// glTF 2.0 through tinygltf into plain data (see gltf_loader.h).
#include "core/scene/gltf_loader.h"

#include "core/common/error.h"
#include "core/scene/gltf_accessor.h"
#include "core/scene/gltf_materials.h"

#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <fstream>

namespace modestack::scene {
namespace {

const std::vector<std::string> kSupportedExtensions{"KHR_lights_punctual", "KHR_materials_emissive_strength"};

std::string lower(std::string text)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
    return text;
}

// tinygltf's messages as one line: lines joined with "; ", trailing blanks dropped.
std::string one_line(const std::string& text)
{
    std::string line;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos)
            end = text.size();
        std::string part = text.substr(start, end - start);
        while (!part.empty() && std::isspace(static_cast<unsigned char>(part.back())))
            part.pop_back();
        if (!part.empty())
            line += (line.empty() ? "" : "; ") + part;
        start = end + 1;
    }
    return line;
}

// The first bytes of a binary glTF.
bool has_glb_magic(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    return in.read(magic, 4) && std::string(magic, 4) == "glTF";
}

tinygltf::Model read_model(const std::string& path)
{
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe || !probe.seekg(0, std::ios::end) || probe.tellg() < 0)
            throw bad_input(path, "cannot read the glTF file (missing, a directory or unreadable)");
        if (probe.tellg() == 0)
            throw bad_input(path, "the glTF file is empty");
    }
    tinygltf::TinyGLTF reader;
    tinygltf::Model model;
    std::string error, warning;
    bool binary = has_glb_magic(path);
    bool ok = binary ? reader.LoadBinaryFromFile(&model, &error, &warning, path)
                     : reader.LoadASCIIFromFile(&model, &error, &warning, path);
    if (!ok) {
        std::string reason = one_line(error.empty() ? warning : error);
        const std::string not_found = "File not found : ";
        if (reason.compare(0, not_found.size(), not_found) == 0) {
            std::string missing = reason.substr(not_found.size());
            throw bad_input(path, "cannot find '" + missing.substr(0, missing.find(';')) +
                                      "', a buffer or image the file refers to (looked next to the file)");
        }
        std::size_t json_error = reason.find("[json.exception.");
        if (json_error != std::string::npos) {
            std::size_t end = reason.find("] ", json_error);
            throw bad_input(path, "not valid JSON: " +
                                      (end == std::string::npos ? reason : reason.substr(end + 2)));
        }
        throw bad_input(path,
                        "cannot load the glTF " + std::string(binary ? "binary" : "file") + ": " + reason);
    }
    return model;
}

void check_extensions(const tinygltf::Model& model, const std::string& path, GltfNotices& notices)
{
    auto supported = [](const std::string& name) {
        return std::find(kSupportedExtensions.begin(), kSupportedExtensions.end(), name) !=
               kSupportedExtensions.end();
    };
    for (const std::string& name : model.extensionsRequired)
        if (!supported(name))
            throw bad_input(path,
                            fmt::format("requires the glTF extension {}, which modestack does not support "
                                        "(supported: KHR_lights_punctual, KHR_materials_emissive_strength)",
                                        name));
    for (const std::string& name : model.extensionsUsed)
        if (!supported(name))
            notices.add(fmt::format("extension {} is not supported and is ignored", name));
}

// Index `index` into a list of `size`, or a bad-input error naming what refers to it.
void check_index(int index, std::size_t size, const std::string& path, const std::string& what)
{
    if (index < 0 || static_cast<std::size_t>(index) >= size)
        throw bad_input(
            path, fmt::format("{} refers to index {}, which does not exist ({} defined)", what, index, size));
}

std::string node_label(const tinygltf::Model& model, int node)
{
    return model.nodes[node].name.empty() ? fmt::format("node {}", node)
                                          : fmt::format("node {} '{}'", node, model.nodes[node].name);
}

void load_nodes(const tinygltf::Model& model, const std::string& path, GltfScene& gltf)
{
    gltf.nodes.resize(model.nodes.size());
    for (std::size_t i = 0; i < model.nodes.size(); ++i) {
        const tinygltf::Node& source = model.nodes[i];
        GltfNode& node = gltf.nodes[i];
        std::string label = node_label(model, static_cast<int>(i));
        node.name = source.name;
        if (source.translation.size() == 3)
            node.translation = {float(source.translation[0]), float(source.translation[1]),
                                float(source.translation[2])};
        if (source.rotation.size() == 4)
            node.rotation = normalize(Quat{float(source.rotation[0]), float(source.rotation[1]),
                                           float(source.rotation[2]), float(source.rotation[3])});
        if (source.scale.size() == 3)
            node.scale = {float(source.scale[0]), float(source.scale[1]), float(source.scale[2])};
        if (source.matrix.size() == 16) {
            node.has_matrix = true;
            for (int k = 0; k < 16; ++k)
                node.matrix.m[k] = float(source.matrix[k]);
        }
        if (source.mesh >= 0) {
            check_index(source.mesh, model.meshes.size(), path, label + " mesh");
            node.mesh = source.mesh;
        }
        if (source.camera >= 0) {
            check_index(source.camera, model.cameras.size(), path, label + " camera");
            node.camera = source.camera;
        }
        auto light = source.extensions.find("KHR_lights_punctual");
        if (light != source.extensions.end() && light->second.Has("light")) {
            int index = light->second.Get("light").GetNumberAsInt();
            check_index(index, model.lights.size(), path, label + " light");
            node.light = index;
        }
        if (source.skin >= 0)
            gltf.notices.add("skins are not supported: skinned meshes are rendered in their bind pose");
        if (!source.weights.empty())
            gltf.notices.add("morph targets are not supported: meshes are rendered without them");
        for (int child : source.children) {
            check_index(child, model.nodes.size(), path, label + " child");
            if (gltf.nodes[child].parent >= 0 || child == static_cast<int>(i))
                throw bad_input(path,
                                fmt::format("{} has more than one parent (the node hierarchy must be a tree)",
                                            node_label(model, child)));
            gltf.nodes[child].parent = static_cast<int>(i);
            node.children.push_back(child);
        }
    }
    // A cycle leaves nodes whose parent chain never ends at a root.
    for (std::size_t i = 0; i < gltf.nodes.size(); ++i) {
        int node = static_cast<int>(i);
        for (std::size_t steps = 0; node >= 0; ++steps, node = gltf.nodes[node].parent)
            if (steps > gltf.nodes.size())
                throw bad_input(path, fmt::format("{} is part of a cycle in the node hierarchy",
                                                  node_label(model, static_cast<int>(i))));
    }
    if (model.scenes.empty()) {
        for (std::size_t i = 0; i < gltf.nodes.size(); ++i)
            if (gltf.nodes[i].parent < 0)
                gltf.roots.push_back(static_cast<int>(i));
        return;
    }
    int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
    check_index(scene, model.scenes.size(), path, "the default scene");
    for (int root : model.scenes[scene].nodes) {
        check_index(root, model.nodes.size(), path, "the scene");
        if (gltf.nodes[root].parent >= 0)
            throw bad_input(path, fmt::format("the scene lists {} as a root, but it has a parent",
                                              node_label(model, root)));
        gltf.roots.push_back(root);
    }
    if (model.scenes.size() > 1)
        gltf.notices.add(
            fmt::format("the file has {} scenes: only scene {} is rendered", model.scenes.size(), scene));
    const tinygltf::Value& extras = model.scenes[scene].extras;
    if (extras.IsObject() && extras.Has("fps") && extras.Get("fps").IsNumber())
        gltf.file_fps = extras.Get("fps").GetNumberAsDouble();
}

const char* mode_name(int mode)
{
    switch (mode) {
    case TINYGLTF_MODE_POINTS:
        return "points";
    case TINYGLTF_MODE_LINE:
        return "lines";
    case TINYGLTF_MODE_LINE_LOOP:
        return "line loops";
    case TINYGLTF_MODE_LINE_STRIP:
        return "line strips";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
        return "triangle strips";
    case TINYGLTF_MODE_TRIANGLE_FAN:
        return "triangle fans";
    default:
        return "unknown modes";
    }
}

void load_meshes(const tinygltf::Model& model, const std::string& path, GltfScene& gltf)
{
    for (std::size_t m = 0; m < model.meshes.size(); ++m) {
        const tinygltf::Mesh& source = model.meshes[m];
        GltfMesh mesh;
        mesh.name = source.name.empty() ? fmt::format("mesh {}", m) : source.name;
        for (std::size_t p = 0; p < source.primitives.size(); ++p) {
            const tinygltf::Primitive& primitive = source.primitives[p];
            if (primitive.mode != TINYGLTF_MODE_TRIANGLES) {
                gltf.notices.add(fmt::format("primitives drawn as {} are not rendered (triangles only)",
                                             mode_name(primitive.mode)));
                continue;
            }
            if (!primitive.targets.empty())
                gltf.notices.add("morph targets are not supported: meshes are rendered without them");
            std::string what = fmt::format("mesh '{}' primitive {}", mesh.name, p);
            auto position = primitive.attributes.find("POSITION");
            if (position == primitive.attributes.end())
                throw bad_input(path, what + " has no POSITION attribute");
            std::vector<float> xyz =
                read_float_accessor(model, position->second, 3, path, what + " positions");
            GltfPrimitive out;
            for (std::size_t v = 0; v + 2 < xyz.size(); v += 3)
                out.positions.push_back({xyz[v], xyz[v + 1], xyz[v + 2]});
            if (primitive.indices >= 0) {
                out.indices = read_index_accessor(model, primitive.indices, out.positions.size(), path,
                                                  what + " indices");
            } else {
                for (std::size_t v = 0; v < out.positions.size(); ++v)
                    out.indices.push_back(static_cast<std::uint32_t>(v));
            }
            if (out.indices.size() % 3 != 0)
                throw bad_input(path, fmt::format("{} has {} indices, not a multiple of 3 (triangles)", what,
                                                  out.indices.size()));
            if (primitive.material >= 0)
                check_index(primitive.material, model.materials.size(), path, what + " material");
            out.material = gltf_material(model, primitive.material, gltf.notices);
            mesh.primitives.push_back(std::move(out));
        }
        gltf.meshes.push_back(std::move(mesh));
    }
}

void load_cameras_and_lights(const tinygltf::Model& model, const std::string& path, GltfScene& gltf)
{
    for (const tinygltf::Camera& source : model.cameras) {
        GltfCamera camera;
        if (source.type == "perspective")
            camera.vertical_fov_radians = static_cast<float>(source.perspective.yfov);
        else
            camera.vertical_fov_radians = 0; // marks "not usable"
        gltf.cameras.push_back(camera);
    }
    // The first perspective camera met depth first from the roots.
    std::vector<int> stack(gltf.roots.rbegin(), gltf.roots.rend());
    while (!stack.empty() && gltf.camera_node < 0) {
        int node = stack.back();
        stack.pop_back();
        int camera = gltf.nodes[node].camera;
        if (camera >= 0) {
            if (gltf.cameras[camera].vertical_fov_radians > 0)
                gltf.camera_node = node;
            else
                gltf.notices.add("orthographic cameras are not supported and are skipped");
        }
        const auto& children = gltf.nodes[node].children;
        stack.insert(stack.end(), children.rbegin(), children.rend());
    }
    if (gltf.camera_node < 0)
        throw bad_input(path,
                        "the scene has no perspective camera (modestack renders through the first one)");
    int camera_nodes = 0;
    for (const GltfNode& node : gltf.nodes)
        camera_nodes += node.camera >= 0;
    if (camera_nodes > 1)
        gltf.notices.add(fmt::format("the file has {} camera nodes: the first in the scene ('{}') is used",
                                     camera_nodes, gltf.nodes[gltf.camera_node].name));

    for (std::size_t l = 0; l < model.lights.size(); ++l) {
        const tinygltf::Light& source = model.lights[l];
        GltfLight light;
        light.name = source.name.empty() ? fmt::format("light {}", l) : source.name;
        if (source.color.size() == 3)
            light.color = {float(source.color[0]), float(source.color[1]), float(source.color[2])};
        light.intensity = static_cast<float>(source.intensity);
        if (source.type == "point")
            light.type = GltfLightType::Point;
        else if (source.type == "spot")
            light.type = GltfLightType::Spot;
        else if (source.type == "directional")
            light.type = GltfLightType::Directional;
        else
            throw bad_input(path, fmt::format("light {} has unknown type '{}'", l, source.type));
        gltf.lights.push_back(light);
    }
    for (const GltfNode& node : gltf.nodes) {
        if (node.light < 0)
            continue;
        const GltfLight& light = gltf.lights[node.light];
        if (light.type == GltfLightType::Point)
            gltf.notices.add(
                "point lights are rendered as emitting spheres of radius 5 cm with the same intensity "
                "(candela / 683 → W/sr)");
        else if (light.type == GltfLightType::Spot)
            gltf.notices.add(
                "spot lights are rendered as 5 cm emitting squares facing the spot's direction: same "
                "on-axis intensity, a cosine lobe instead of the cone angles");
        else
            gltf.notices.add("directional lights are rendered as a large emitting square outside the scene's "
                             "bounds (about the light's illuminance at the centre; closed rooms block it)");
    }
    if (std::any_of(model.lights.begin(), model.lights.end(), [](const auto& l) { return l.range > 0; }))
        gltf.notices.add("light range is ignored (lights fall off with the inverse square only)");
}

void load_animations(const tinygltf::Model& model, const std::string& path, GltfScene& gltf)
{
    if (model.animations.size() > 1)
        gltf.notices.add(
            fmt::format("the file has {} animations: they are played together", model.animations.size()));
    for (std::size_t a = 0; a < model.animations.size(); ++a) {
        const tinygltf::Animation& animation = model.animations[a];
        for (std::size_t c = 0; c < animation.channels.size(); ++c) {
            const tinygltf::AnimationChannel& source = animation.channels[c];
            std::string what = fmt::format("animation {} channel {}", a, c);
            GltfChannel channel;
            if (source.target_path == "translation")
                channel.property = AnimatedProperty::Translation;
            else if (source.target_path == "rotation")
                channel.property = AnimatedProperty::Rotation;
            else if (source.target_path == "scale")
                channel.property = AnimatedProperty::Scale;
            else {
                gltf.notices.add(
                    fmt::format("animation of '{}' is not supported and is ignored", source.target_path));
                continue;
            }
            if (source.target_node < 0) // allowed by glTF for extensions; nothing to animate here
                continue;
            check_index(source.target_node, model.nodes.size(), path, what + " target node");
            check_index(source.sampler, animation.samplers.size(), path, what + " sampler");
            const tinygltf::AnimationSampler& sampler = animation.samplers[source.sampler];
            KeyframeTrack& track = channel.track;
            if (sampler.interpolation == "LINEAR")
                track.interpolation = Interpolation::Linear;
            else if (sampler.interpolation == "STEP")
                track.interpolation = Interpolation::Step;
            else if (sampler.interpolation == "CUBICSPLINE") {
                track.interpolation = Interpolation::CubicSpline;
                gltf.notices.add("CUBICSPLINE animation is approximated as LINEAR between its keys (tangents "
                                 "ignored)");
            } else
                throw bad_input(
                    path, fmt::format("{} has unknown interpolation '{}'", what, sampler.interpolation));
            track.components = channel.property == AnimatedProperty::Rotation ? 4 : 3;
            track.times = read_float_accessor(model, sampler.input, 1, path, what + " key times");
            track.values =
                read_float_accessor(model, sampler.output, track.components, path, what + " key values");
            std::size_t per_key =
                (track.interpolation == Interpolation::CubicSpline ? 3 : 1) * track.components;
            if (track.times.empty() || track.values.size() != track.times.size() * per_key)
                throw bad_input(path,
                                fmt::format("{} has {} key times but {} values", what, track.times.size(),
                                            track.values.size() / track.components));
            for (std::size_t k = 1; k < track.times.size(); ++k)
                if (!(track.times[k] > track.times[k - 1]))
                    throw bad_input(path, fmt::format("{} key times are not increasing", what));
            if (track.times.front() < 0)
                throw bad_input(path, fmt::format("{} starts at a negative time", what));
            if (gltf.nodes[source.target_node].has_matrix)
                throw bad_input(path, fmt::format("{} animates {}, which has a matrix (glTF forbids it)",
                                                  what, node_label(model, source.target_node)));
            channel.node = source.target_node;
            gltf.end_time_seconds = std::max(gltf.end_time_seconds, track.times.back());
            gltf.channels.push_back(std::move(channel));
        }
    }
}

} // namespace

bool is_gltf_path(const std::string& name)
{
    std::string low = lower(name);
    auto ends_with = [&](const std::string& suffix) {
        return low.size() > suffix.size() &&
               low.compare(low.size() - suffix.size(), suffix.size(), suffix) == 0;
    };
    return ends_with(".gltf") || ends_with(".glb");
}

GltfScene load_gltf(const std::string& path)
{
    tinygltf::Model model = read_model(path);
    GltfScene gltf;
    gltf.file = path;
    check_extensions(model, path, gltf.notices);
    load_nodes(model, path, gltf);
    load_meshes(model, path, gltf);
    load_cameras_and_lights(model, path, gltf);
    load_animations(model, path, gltf);
    return gltf;
}

} // namespace modestack::scene
