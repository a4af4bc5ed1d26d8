// The light transport of one camera sample: a unidirectional path tracer for
// Lambertian surfaces with next-event estimation to the emissive triangles,
// combined with BSDF (cosine) sampling by multiple importance sampling (power
// heuristic), and Russian roulette after a few bounces. It returns the sample's
// light split the way the AOVs need it (emitted, one bounce, more bounces) plus
// the first hit's surface data; render.cpp averages samples into pixels.
#pragma once

#include "core/render/ray_scene.h"
#include "core/render/sampler.h"
#include "core/scene/scene.h"

#include <cstdint>
#include <vector>

namespace modestack::render {

/// The emissive triangles of a scene, chosen in proportion to their power.
class LightSet {
public:
    explicit LightSet(const scene::Scene& scene);

    /// A point chosen on the lights, its front normal, emission and area density.
    struct Sample {
        scene::Vec3 point, normal, emission;
        float area_pdf = 0; ///< probability per square metre of choosing `point`
    };
    bool empty() const { return m_triangles.empty(); }
    /// Chooses a triangle with `select` and a uniform point on it with `point`.
    Sample sample(float select, Sample2 point) const;
    /// Area density with which sample() chooses points of this triangle (0 if it is no light).
    float area_pdf(int mesh_index, int triangle_index) const;

private:
    struct Triangle {
        scene::Vec3 p0, edge1, edge2, normal, emission;
        float area;
    };
    std::vector<Triangle> m_triangles;
    std::vector<float> m_cumulative; // normalised running sum of power, last entry 1
    std::vector<float> m_select_pdf; // power / total power, per triangle
    std::vector<int> m_first_light;  // per mesh: index of its first triangle in m_triangles, or −1
};

/// What one camera sample saw; light terms are radiance towards the camera.
struct PathSample {
    bool hit = false;      ///< the camera ray hit a surface
    scene::Vec3 emitted;   ///< emission of the first hit
    scene::Vec3 direct;    ///< light after exactly one bounce (already × albedo)
    scene::Vec3 indirect;  ///< light after two or more bounces (already × albedo)
    scene::Vec3 albedo;    ///< albedo of the first hit
    scene::Vec3 normal;    ///< unit normal of the first hit, facing the camera
    scene::Vec3 position;  ///< first hit, world space
    float depth = 0;       ///< first hit's distance along the camera's view axis
    int mesh_index = -1;   ///< first hit's mesh
    int triangle_index = -1; ///< first hit's triangle within the mesh
    float b1 = 0, b2 = 0;  ///< first hit's barycentric weights of the triangle's 2nd and 3rd vertices
    std::int64_t rays = 0; ///< rays cast for this sample
};

/// Everything a sample needs that is shared by the whole frame.
struct TraceContext {
    const scene::Scene* scene;
    const RayScene* rays;
    const LightSet* lights;
    int max_depth; ///< maximum number of bounces (1 = direct light only)
    scene::Vec3 camera_forward;
};

/// Traces sample `sample_index` of a pixel from `origin` along unit `direction`.
/// Uses dimension pairs 1, 2, 3, ... of `sampler` (pair 0 is the pixel position).
PathSample trace_path(const TraceContext& context, scene::Vec3 origin, scene::Vec3 direction,
                      const PixelSampler& sampler, std::uint32_t sample_index);

/// A path that starts on a known surface point instead of at the camera: the
/// bake of object-space points (surface_points.h). The point is vertex 0, seen
/// from the front side of its triangle, with albedo 1, so `direct` and `indirect`
/// are the light arriving there (as DiffDir and DiffInd hold it).
struct SurfaceStart {
    scene::Vec3 point;
    scene::Vec3 normal; ///< the triangle's unit front normal
    int mesh_index = -1;
    int triangle_index = -1;
};

/// Traces sample `sample_index` of a path from `start`; uses the same dimension
/// pairs as trace_path.
PathSample trace_from_surface(const TraceContext& context, const SurfaceStart& start, const PixelSampler& sampler,
                              std::uint32_t sample_index);

} // namespace modestack::render
