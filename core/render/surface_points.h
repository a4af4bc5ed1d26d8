// The fixed surface sample points of object-space denoising (seed [0079]-[0081]):
// indirect light is baked at points that stay on the same spot of their object in
// every frame, so the denoiser sees one points × frames matrix per shot however
// the camera and the objects move.
//
// How the points are chosen: every triangle of the scene's rest pose (the shot's
// first frame) gets a regular barycentric lattice, the points (i/n, j/n) with
// i + j ≤ n, where n = ceil(longest edge / spacing). So points are spread by area,
// no edge of a lattice cell is longer than `spacing`, and a point is named by
// (mesh, triangle, i, j) alone: its id does not depend on where the object is.
// Ids run mesh by mesh, triangle by triangle, row j by row j, i within a row.
// A moving or deforming mesh carries its points along (the barycentric
// coordinates stay fixed), so every frame must have the rest pose's meshes and
// triangle counts. Points sit on the front side (winding order) of each triangle.
#pragma once

#include "core/scene/scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::render {

/// A point's weight in the value seen by some surface position.
struct PointWeight {
    std::int64_t id = -1;
    float weight = 0;
};

/// Where a point sits: a triangle and barycentric weights of its 2nd and 3rd vertices.
struct PointPlace {
    int mesh = 0, triangle = 0;
    float b1 = 0, b2 = 0;
};

/// The lattices of every triangle of a scene.
class SurfacePoints {
public:
    /// Lattices on `rest` with cells no longer than `spacing` metres (> 0).
    /// Throws a usage error for a spacing ≤ 0 or one giving more than `max_points`.
    SurfacePoints(const scene::Scene& rest, double spacing, std::int64_t max_points);

    /// The spacing that gives about `target` points on `rest` (at least 1 point per
    /// triangle is always placed, so small targets give more).
    static double spacing_for_count(const scene::Scene& rest, std::int64_t target);

    std::int64_t count() const { return m_count; }
    double spacing() const { return m_spacing; }
    int mesh_count() const { return static_cast<int>(m_first_id.size()); }
    /// Lattice resolution n of a triangle (its points are (i/n, j/n), i + j ≤ n).
    int resolution(int mesh, int triangle) const { return m_resolution[mesh][triangle]; }
    /// Id of lattice point (i, j) of a triangle.
    std::int64_t id(int mesh, int triangle, int i, int j) const;

    /// Throws a bad-input error naming `what` (e.g. "scene 'switch' frame 30") if
    /// `scene` does not have the rest pose's meshes and triangle counts.
    void check_topology(const scene::Scene& scene, const std::string& what) const;

    /// The three lattice points around barycentric position (b1, b2) of a triangle
    /// (weight of p1 and p2; p0 has 1 − b1 − b2) and their interpolation weights,
    /// which sum to 1: linear interpolation over the lattice cell.
    void interpolate(int mesh, int triangle, float b1, float b2, PointWeight out[3]) const;

    /// Every point's place, indexed by id (made once, with the lattices).
    const std::vector<PointPlace>& places() const { return m_places; }

private:
    std::vector<std::vector<int>> m_resolution;         // [mesh][triangle] → n
    std::vector<std::vector<std::int64_t>> m_first_id;  // [mesh][triangle] → id of (0, 0)
    std::vector<PointPlace> m_places;                   // by id
    std::int64_t m_count = 0;
    double m_spacing = 0;
};

} // namespace modestack::render
