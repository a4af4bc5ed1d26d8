// The ray-query side of one frame's scene: the Embree BVH over every mesh, built
// once per frame (geometry moves between frames), answering closest-hit and
// shadow queries. The Embree types stay inside ray_scene.cpp so that this header
// can be included anywhere in core/render without pulling in Embree.
#pragma once

#include "core/scene/scene.h"

#include <memory>

namespace modestack::render {

/// The closest surface a ray hits.
struct RayHit {
    float distance = 0;           ///< along the (unit) ray direction, in metres
    int mesh_index = -1;          ///< index into Scene::meshes
    int triangle_index = -1;      ///< triangle within that mesh
    scene::Vec3 geometric_normal; ///< unit normal of the triangle, front side (winding order)
    float b1 = 0, b2 = 0;         ///< barycentric weights of the triangle's 2nd and 3rd vertices
};

/// An Embree scene built from a scene::Scene. Queries are thread-safe.
class RayScene {
public:
    /// Builds the BVH. Throws a bad-input error if a mesh's indices are out of
    /// range, an internal error if Embree fails.
    explicit RayScene(const scene::Scene& scene);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    /// Closest hit of the ray origin + t·direction, 0 ≤ t < max_distance; false on a miss.
    /// `direction` must have unit length.
    bool intersect(scene::Vec3 origin, scene::Vec3 direction, float max_distance, RayHit& hit) const;
    /// True if anything lies on origin + t·direction, 0 ≤ t < max_distance.
    bool occluded(scene::Vec3 origin, scene::Vec3 direction, float max_distance) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

} // namespace modestack::render
