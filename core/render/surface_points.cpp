// Barycentric lattices per triangle (see surface_points.h).
#include "core/render/surface_points.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace modestack::render {
namespace {

using scene::Vec3;

float longest_edge(const scene::Mesh& mesh, std::size_t triangle)
{
    auto [p0, p1, p2] = mesh.corners(triangle);
    return std::max({scene::length(p1 - p0), scene::length(p2 - p1), scene::length(p0 - p2)});
}

int resolution_for(float edge, double spacing)
{
    // At least one cell; the cap keeps (n+1)(n+2)/2 well inside 64 bits.
    double n = std::ceil(static_cast<double>(edge) / spacing);
    return static_cast<int>(std::clamp(n, 1.0, 1e6));
}

std::int64_t lattice_points(int n)
{
    return static_cast<std::int64_t>(n + 1) * (n + 2) / 2;
}

std::int64_t count_for(const scene::Scene& rest, double spacing)
{
    std::int64_t count = 0;
    for (const scene::Mesh& mesh : rest.meshes)
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
            count += lattice_points(resolution_for(longest_edge(mesh, t), spacing));
    return count;
}

// Offset of row j in a lattice of resolution n: rows j' < j hold n + 1 − j' points.
std::int64_t row_offset(int n, int j)
{
    return static_cast<std::int64_t>(j) * (n + 1) - static_cast<std::int64_t>(j) * (j - 1) / 2;
}

} // namespace

SurfacePoints::SurfacePoints(const scene::Scene& rest, double spacing, std::int64_t max_points) : m_spacing(spacing)
{
    if (!(spacing > 0) || !std::isfinite(spacing))
        throw usage_error(fmt::format("surface point spacing must be positive (got {})", spacing));
    for (const scene::Mesh& mesh : rest.meshes) {
        m_resolution.emplace_back();
        m_first_id.emplace_back();
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
            int n = resolution_for(longest_edge(mesh, t), spacing);
            m_resolution.back().push_back(n);
            m_first_id.back().push_back(m_count);
            m_count += lattice_points(n);
            if (m_count > max_points)
                throw usage_error(fmt::format("a surface point spacing of {:.4g} m places more than {} points: "
                                              "use a larger spacing or fewer points",
                                              spacing, max_points));
        }
    }
    // Ids run mesh by mesh, triangle by triangle, row j by row j, i within a row.
    m_places.reserve(static_cast<std::size_t>(m_count));
    for (int mesh = 0; mesh < mesh_count(); ++mesh)
        for (int triangle = 0; triangle < static_cast<int>(m_resolution[mesh].size()); ++triangle) {
            const int n = m_resolution[mesh][triangle];
            for (int j = 0; j <= n; ++j)
                for (int i = 0; i + j <= n; ++i)
                    m_places.push_back({mesh, triangle, static_cast<float>(i) / static_cast<float>(n),
                                        static_cast<float>(j) / static_cast<float>(n)});
        }
}

double SurfacePoints::spacing_for_count(const scene::Scene& rest, std::int64_t target)
{
    double longest = 0;
    for (const scene::Mesh& mesh : rest.meshes)
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
            longest = std::max(longest, static_cast<double>(longest_edge(mesh, t)));
    if (longest <= 0)
        return 1.0;
    // The count falls as the spacing grows: bisect in log space between a spacing
    // giving one cell per triangle and one a million times finer.
    double low = longest * 1e-6, high = longest;
    for (int step = 0; step < 60; ++step) {
        double middle = std::sqrt(low * high);
        (count_for(rest, middle) > target ? low : high) = middle;
    }
    return high;
}

std::int64_t SurfacePoints::id(int mesh, int triangle, int i, int j) const
{
    return m_first_id[mesh][triangle] + row_offset(m_resolution[mesh][triangle], j) + i;
}

void SurfacePoints::check_topology(const scene::Scene& scene, const std::string& what) const
{
    if (static_cast<int>(scene.meshes.size()) != mesh_count())
        throw bad_input(what, fmt::format("has {} meshes, the rest pose (first frame) {}: object space needs the "
                                          "same meshes in every frame",
                                          scene.meshes.size(), mesh_count()));
    for (int mesh = 0; mesh < mesh_count(); ++mesh)
        if (scene.meshes[mesh].triangle_count() != m_resolution[mesh].size())
            throw bad_input(what, fmt::format("mesh '{}' has {} triangles, {} in the rest pose (first frame): "
                                              "object space needs the same triangles in every frame",
                                              scene.meshes[mesh].name, scene.meshes[mesh].triangle_count(),
                                              m_resolution[mesh].size()));
}

void SurfacePoints::interpolate(int mesh, int triangle, float b1, float b2, PointWeight out[3]) const
{
    const int n = m_resolution[mesh][triangle];
    const float a = std::clamp(b1, 0.0f, 1.0f) * static_cast<float>(n);
    const float b = std::clamp(b2, 0.0f, 1.0f) * static_cast<float>(n);
    // The cell's lower corner (i0, j0) with i0 + j0 ≤ n − 1.
    int j0 = std::min(static_cast<int>(b), n - 1);
    int i0 = std::min(static_cast<int>(a), n - 1 - j0);
    float fa = std::clamp(a - static_cast<float>(i0), 0.0f, 1.0f);
    float fb = std::clamp(b - static_cast<float>(j0), 0.0f, 1.0f);
    if (fa + fb <= 1 || i0 + j0 + 2 > n) {
        // Lower cell (i0, j0), (i0 + 1, j0), (i0, j0 + 1); clamped into it at the hypotenuse.
        float sum = fa + fb;
        if (sum > 1) {
            fa /= sum;
            fb /= sum;
        }
        out[0] = {id(mesh, triangle, i0, j0), 1 - fa - fb};
        out[1] = {id(mesh, triangle, i0 + 1, j0), fa};
        out[2] = {id(mesh, triangle, i0, j0 + 1), fb};
    } else {
        // Upper cell (i0 + 1, j0 + 1), (i0, j0 + 1), (i0 + 1, j0).
        out[0] = {id(mesh, triangle, i0 + 1, j0 + 1), fa + fb - 1};
        out[1] = {id(mesh, triangle, i0, j0 + 1), 1 - fa};
        out[2] = {id(mesh, triangle, i0 + 1, j0), 1 - fb};
    }
}

} // namespace modestack::render
