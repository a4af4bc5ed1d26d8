// Exports a frame of a built-in scene for Embree's own `pathtracer` tutorial
// (Debian embree-tools), so bench/render.sh can time both tracers on the same
// room: the non-emissive meshes go to an .obj/.mtl (Kd = albedo) and an .ecs
// file holds the tutorial's command-line options: the .obj, the camera and the
// light. Each emissive quad becomes a point light 1 cm below its centre with the
// quad's on-axis intensity (radiance × area): Embree 3.13's tutorial parses an
// XML QuadLight but renders it black, and a point light costs the same one
// shadow ray per path vertex as our area-light sample. The light quad itself is
// therefore not in the .obj (two triangles fewer than our scene).
//
//   bench_export_scene SCENE FRAME DIRECTORY   → DIRECTORY/room.obj, room.mtl, room.ecs
#include "core/scene/builtin_scenes.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace {

using modestack::scene::Vec3;

Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 4) {
        std::fprintf(stderr, "usage: bench_export_scene SCENE FRAME DIRECTORY\n");
        return 2;
    }
    const std::string directory = argv[3];
    modestack::scene::Scene scene;
    try {
        scene = modestack::scene::make_builtin_scene(argv[1], std::atoi(argv[2]));
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench_export_scene: %s\n", error.what());
        return 1;
    }
    std::ofstream obj(directory + "/room.obj"), mtl(directory + "/room.mtl"), ecs(directory + "/room.ecs");
    if (!obj || !mtl || !ecs) {
        std::fprintf(stderr, "bench_export_scene: cannot write into %s\n", directory.c_str());
        return 1;
    }
    obj << "# modestack built-in scene '" << argv[1] << "' frame " << argv[2] << " (bench/export_scene)\n";
    obj << "mtllib room.mtl\n";
    std::string lights_options;
    size_t first_vertex = 1, triangles = 0, lights = 0;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const auto& mesh = scene.meshes[m];
        std::string name = "m" + std::to_string(m);
        if (mesh.material.is_emissive()) {
            // A quad light: two triangles (0 1 2), (0 2 3) of four vertices p0..p3.
            if (mesh.positions.size() != 4) {
                std::fprintf(stderr, "bench_export_scene: light '%s' is not a quad\n", mesh.name.c_str());
                return 1;
            }
            Vec3 p0 = mesh.positions[0], e1 = sub(mesh.positions[1], p0), e2 = sub(mesh.positions[3], p0);
            Vec3 normal{e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
            float area = std::sqrt(normal.x * normal.x + normal.y * normal.y + normal.z * normal.z);
            Vec3 center{p0.x + 0.5f * (e1.x + e2.x), p0.y + 0.5f * (e1.y + e2.y) - 0.01f, p0.z + 0.5f * (e1.z + e2.z)};
            const Vec3& radiance = mesh.material.emission;
            lights_options += "--pointlight " + std::to_string(center.x) + " " + std::to_string(center.y) + " " +
                              std::to_string(center.z) + " " + std::to_string(radiance.x * area) + " " +
                              std::to_string(radiance.y * area) + " " + std::to_string(radiance.z * area) + "\n";
            ++lights;
            continue;
        }
        mtl << "newmtl " << name << "\nKa 0 0 0\nKd " << mesh.material.albedo.x << " " << mesh.material.albedo.y
            << " " << mesh.material.albedo.z << "\nKs 0 0 0\n\n";
        obj << "o " << name << "_" << mesh.name.substr(0, mesh.name.find(' ')) << "\nusemtl " << name << "\n";
        for (const Vec3& p : mesh.positions)
            obj << "v " << p.x << " " << p.y << " " << p.z << "\n";
        for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
            obj << "f " << first_vertex + mesh.indices[i] << " " << first_vertex + mesh.indices[i + 1] << " "
                << first_vertex + mesh.indices[i + 2] << "\n";
        first_vertex += mesh.positions.size();
        triangles += mesh.triangle_count();
    }
    const auto& camera = scene.camera;
    ecs << "-i room.obj\n" << lights_options << "--vp " << camera.position.x << " " << camera.position.y << " "
        << camera.position.z << " --vi " << camera.look_at.x << " " << camera.look_at.y << " " << camera.look_at.z
        << " --vu " << camera.up.x << " " << camera.up.y << " " << camera.up.z << " --fov "
        << camera.vertical_fov_degrees << "\n";
    std::printf("{\"triangles\": %zu, \"lights\": %zu}\n", triangles, lights);
    return 0;
}
