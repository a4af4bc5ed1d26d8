// Loading glTF files: the committed test scene (its animated camera and objects
// at given times, light and material conversion, notices), and bad files, each
// refused with one line naming the file and the problem.
#include "core/common/error.h"
#include "core/scene/gltf_animation.h"
#include "core/scene/gltf_loader.h"
#include "core/scene/gltf_materials.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <cmath>
#include <fstream>

using namespace modestack;
using namespace modestack::scene;

namespace {

const std::string kRoom = std::string(MODESTACK_SOURCE_DIR) + "/testdata/gltf/room.gltf";

void check_vec3(Vec3 actual, Vec3 expected, double epsilon = 1e-5)
{
    CHECK(actual.x == doctest::Approx(expected.x).epsilon(epsilon));
    CHECK(actual.y == doctest::Approx(expected.y).epsilon(epsilon));
    CHECK(actual.z == doctest::Approx(expected.z).epsilon(epsilon));
}

int node_named(const GltfScene& gltf, const std::string& name)
{
    for (std::size_t i = 0; i < gltf.nodes.size(); ++i)
        if (gltf.nodes[i].name == name)
            return static_cast<int>(i);
    FAIL("no node " << name);
    return -1;
}

void write_text(const std::string& path, const std::string& text)
{
    std::ofstream(path, std::ios::binary) << text;
}

// One triangle (3 float positions = 36 bytes in `bin`) seen by a camera; `extra`
// is spliced into the top-level JSON object; `count` is the position count.
std::string triangle_json(const std::string& bin, const std::string& extra = "", int count = 3,
                          bool with_camera = true)
{
    std::string camera_node = with_camera ? R"(,{"camera":0,"translation":[0,0,3]})" : "";
    std::string scene_nodes = with_camera ? "[0,1]" : "[0]";
    return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":)" + scene_nodes + R"(}],
  "nodes":[{"mesh":0})" +
           camera_node + R"(],
  "cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}],
  "meshes":[{"name":"tri","primitives":[{"attributes":{"POSITION":0}}]}],
  "accessors":[{"bufferView":0,"componentType":5126,"count":)" +
           std::to_string(count) + R"(,"type":"VEC3"}],
  "bufferViews":[{"buffer":0,"byteLength":36}],
  "buffers":[{"uri":")" +
           bin + R"(","byteLength":36}])" + extra + "}";
}

void write_triangle_bin(const std::string& path)
{
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(positions), sizeof positions);
}

std::string load_error(const std::string& path)
{
    try {
        load_gltf(path);
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::BadInput);
        CHECK(std::string(error.what()).find('\n') == std::string::npos);
        return error.what();
    }
    FAIL("no error for " << path);
    return {};
}

} // namespace

TEST_CASE("the test room loads: hierarchy, meshes, camera, light, emissive material, 24 fps")
{
    GltfScene gltf = load_gltf(kRoom);
    CHECK(gltf.file_fps == 24);
    CHECK(gltf.end_time_seconds == doctest::Approx(23.0 / 24.0));
    CHECK(gltf_last_frame(gltf, 24) == 24);
    CHECK(gltf.nodes[gltf.camera_node].name == "camera");
    CHECK(gltf.nodes[node_named(gltf, "rider")].parent == node_named(gltf, "mover"));
    REQUIRE(gltf.lights.size() == 1);
    CHECK(gltf.lights[0].type == GltfLightType::Point);
    CHECK(gltf.notices.contains("point lights are rendered as emitting spheres"));
    // panel: emissiveFactor (1, 0.85, 0.6) × KHR_materials_emissive_strength 6.
    const GltfMesh& panel = gltf.meshes[gltf.nodes[node_named(gltf, "panel")].mesh];
    check_vec3(panel.primitives.at(0).material.emission, {6, 5.1f, 3.6f});
    const GltfMesh& left = gltf.meshes[gltf.nodes[node_named(gltf, "left")].mesh];
    check_vec3(left.primitives.at(0).material.albedo, {0.63f, 0.065f, 0.05f});
    Scene frame = gltf_scene_at(gltf, 0);
    CHECK(frame.meshes.size() == 10); // 6 walls, panel, mover, rider, lamp
}

TEST_CASE("the test room's camera and mover are where Blender keyed them, at the frames' times")
{
    GltfScene gltf = load_gltf(kRoom);
    int camera = gltf.camera_node, mover = node_named(gltf, "mover"), rider = node_named(gltf, "rider");
    // Keys (Blender frames 0 and 23 = our frames 1 and 24; Blender z-up → glTF y-up):
    // camera from (-0.7, 1.3, 1.3) to (0.7, 1.3, 1.3); mover x -0.8, 0 (our frame 12), 0.8.
    check_vec3(transform_point(gltf_world_matrices(gltf, gltf_frame_time(1, 24))[camera], {}),
               {-0.7f, 1.3f, 1.3f});
    check_vec3(transform_point(gltf_world_matrices(gltf, gltf_frame_time(24, 24))[camera], {}),
               {0.7f, 1.3f, 1.3f});
    Vec3 middle = transform_point(gltf_world_matrices(gltf, 11.5f / 24)[camera], {});
    CHECK(middle.x == doctest::Approx(0).epsilon(1e-5).scale(1));
    std::vector<Mat4> frame_12 = gltf_world_matrices(gltf, gltf_frame_time(12, 24));
    check_vec3(transform_point(frame_12[mover], {}), {0, 0.2f, -0.2f});
    // The rider sits 0.75 up in the mover's space (scale 0.4): 0.2 + 0.3.
    check_vec3(transform_point(frame_12[rider], {}), {0, 0.5f, -0.2f});
    // The camera looks at Blender's target (0, 0.3, 0.8) → glTF (0, 0.8, -0.3) in every frame.
    for (int frame : {1, 7, 24}) {
        Scene scene = gltf_scene_at(gltf, gltf_frame_time(frame, 24));
        Vec3 forward = normalize(scene.camera.look_at - scene.camera.position);
        Vec3 to_target = normalize(Vec3{0, 0.8f, -0.3f} - scene.camera.position);
        CHECK(dot(forward, to_target) == doctest::Approx(1).epsilon(1e-3));
    }
}

TEST_CASE("bad glTF files give one line naming the file and the problem")
{
    testkit::TempDir dir;
    write_triangle_bin(dir.file("tri.bin"));
    write_text(dir.file("good.gltf"), triangle_json("tri.bin"));
    CHECK_NOTHROW(load_gltf(dir.file("good.gltf")));

    CHECK(load_error(dir.file("absent.gltf")) ==
          dir.file("absent.gltf") + ": cannot read the glTF file (missing, a directory or unreadable)");
    write_text(dir.file("nobin.gltf"), triangle_json("missing.bin"));
    CHECK(load_error(dir.file("nobin.gltf")) ==
          dir.file("nobin.gltf") +
              ": cannot find 'missing.bin', a buffer or image the file refers to (looked next to the file)");
    write_text(dir.file("bad.gltf"), "{ \"asset\": { \"version\": \"2.0\" ");
    CHECK(load_error(dir.file("bad.gltf")) ==
          dir.file("bad.gltf") +
              ": not valid JSON: parse error at line 1, column 31: syntax error while parsing "
              "object - unexpected end of input; expected '}'");
    write_text(dir.file("draco.gltf"),
               triangle_json("tri.bin", R"(,"extensionsUsed":["KHR_draco_mesh_compression"],)"
                                        R"("extensionsRequired":["KHR_draco_mesh_compression"])"));
    CHECK(load_error(dir.file("draco.gltf")) ==
          dir.file("draco.gltf") +
              ": requires the glTF extension KHR_draco_mesh_compression, which modestack "
              "does not support (supported: KHR_lights_punctual, KHR_materials_emissive_strength)");
    write_text(dir.file("nocamera.gltf"), triangle_json("tri.bin", "", 3, false));
    CHECK(load_error(dir.file("nocamera.gltf")) ==
          dir.file("nocamera.gltf") +
              ": the scene has no perspective camera (modestack renders through the first one)");
    write_text(dir.file("overrun.gltf"), triangle_json("tri.bin", "", 4));
    CHECK(load_error(dir.file("overrun.gltf")) ==
          dir.file("overrun.gltf") +
              ": accessor 0 (mesh 'tri' primitive 0 positions): needs 48 bytes but its buffer "
              "view 0 has 36");
}

TEST_CASE("a base colour texture becomes its average linear colour times the factor, reported once")
{
    testkit::TempDir dir;
    write_triangle_bin(dir.file("tri.bin"));
    // A 2×1 PNG: sRGB (1, 0, 1) and (0, 1, 1) → linear average (0.5, 0.5, 1).
    std::string json = triangle_json(
        "tri.bin",
        R"(,"materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.5,0.8,0.9,1],"metallicFactor":0,)"
        R"("baseColorTexture":{"index":0}}}],"textures":[{"source":0}],"images":[{"uri":"data:image/png;base64,)"
        R"(iVBORw0KGgoAAAANSUhEUgAAAAIAAAABCAIAAAB7QOjdAAAADUlEQVR4nGP4zwCE/wEM+gP92V8GAgAAAABJRU5ErkJggg=="}])");
    const std::string attributes = R"("attributes":{"POSITION":0})";
    json.replace(json.find(attributes), attributes.size(), attributes + R"(,"material":0)");
    write_text(dir.file("textured.gltf"), json);
    GltfScene gltf = load_gltf(dir.file("textured.gltf"));
    check_vec3(gltf.meshes.at(0).primitives.at(0).material.albedo, {0.25f, 0.4f, 0.9f});
    CHECK(gltf.notices.messages() ==
          std::vector<std::string>{"base colour textures are replaced by their average colour (no texture "
                                   "lookups)"});
    unsigned char grey16[4] = {0xff, 0xff, 0, 0}; // 16-bit grey: white and black
    check_vec3(average_srgb_colour(grey16, 2, 1, 1, 16), {0.5f, 0.5f, 0.5f});
}

TEST_CASE("a .glb (binary glTF with its buffer inside) loads like the .gltf, a truncated one is refused")
{
    testkit::TempDir dir;
    std::string json = triangle_json("unused.bin");
    json.replace(json.find(R"("uri":"unused.bin",)"), std::string(R"("uri":"unused.bin",)").size(), "");
    json.append((4 - json.size() % 4) % 4, ' ');
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    std::string glb = "glTF" + u32(2) + u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + 36)) +
                      u32(static_cast<std::uint32_t>(json.size())) + "JSON" + json + u32(36) +
                      std::string("BIN\0", 4) + std::string(reinterpret_cast<const char*>(positions), 36);
    write_text(dir.file("tri.glb"), glb);
    GltfScene gltf = load_gltf(dir.file("tri.glb"));
    REQUIRE(gltf.meshes.size() == 1);
    check_vec3(gltf.meshes[0].primitives.at(0).positions.at(1), {1, 0, 0});
    write_text(dir.file("short.glb"), glb.substr(0, 8));
    CHECK(load_error(dir.file("short.glb")) ==
          dir.file("short.glb") + ": cannot load the glTF binary: Too short data size for glTF Binary.");
}

TEST_CASE("unsupported features are reported once each, not silently ignored")
{
    testkit::TempDir dir;
    write_triangle_bin(dir.file("tri.bin"));
    write_text(dir.file("extra.gltf"),
               triangle_json("tri.bin", R"(,"extensionsUsed":["KHR_materials_clearcoat"])"));
    GltfScene gltf = load_gltf(dir.file("extra.gltf"));
    CHECK(gltf.notices.messages() ==
          std::vector<std::string>{"extension KHR_materials_clearcoat is not supported and is ignored"});
    GltfNotices notices;
    notices.add("a");
    notices.add("b");
    notices.add("a");
    CHECK(notices.messages() == std::vector<std::string>{"a", "b"});
}
