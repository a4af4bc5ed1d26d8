// Path tracing with next-event estimation and MIS (see path_tracer.h).
//
// Path lengths: the first hit is vertex 0. Next-event estimation at vertex v and
// an emitter hit by BSDF sampling at vertex v+1 both make paths of v+1 bounces,
// and both are only taken while v < max_depth, so the two strategies cover the
// same set of paths and the MIS weights sum to one on each of them.
#include "core/render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace modestack::render {

using scene::Vec3;

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInversePi = 1.0f / kPi;
// Ray origins are pushed off the surface by this much (metres) along the normal:
// the rooms are about 2 m across, float precision there is ~1e-7 m.
constexpr float kSurfaceOffset = 1e-4f;
// Russian roulette starts after this many bounces (unbiased: survivors are reweighted).
constexpr int kRouletteStartVertex = 3;

float power_heuristic(float pdf_chosen, float pdf_other)
{
    float a = pdf_chosen * pdf_chosen, b = pdf_other * pdf_other;
    return a / (a + b);
}

// Orthonormal basis around unit n (Duff et al. 2017, branchless).
void make_basis(Vec3 n, Vec3& tangent, Vec3& bitangent)
{
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    tangent = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    bitangent = {b, sign + n.y * n.y * a, -n.y};
}

// Cosine-weighted direction about n via the concentric disk map, which keeps the
// sample pair's stratification.
Vec3 sample_cosine_hemisphere(Vec3 n, Sample2 s)
{
    float x = 2 * s.u - 1, y = 2 * s.v - 1, r = 0, phi = 0;
    if (x != 0 || y != 0) {
        if (std::fabs(x) > std::fabs(y)) {
            r = x;
            phi = (kPi / 4) * (y / x);
        } else {
            r = y;
            phi = (kPi / 2) - (kPi / 4) * (x / y);
        }
    }
    float dx = r * std::cos(phi), dy = r * std::sin(phi);
    float dz = std::sqrt(std::max(0.0f, 1 - dx * dx - dy * dy));
    Vec3 tangent, bitangent;
    make_basis(n, tangent, bitangent);
    return scene::normalize(tangent * dx + bitangent * dy + n * dz);
}

} // namespace

LightSet::LightSet(const scene::Scene& scene)
{
    double total_power = 0;
    std::vector<double> power;
    for (const scene::Mesh& mesh : scene.meshes) {
        m_first_light.push_back(-1);
        if (!mesh.material.is_emissive())
            continue;
        m_first_light.back() = static_cast<int>(m_triangles.size());
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
            auto [p0, p1, p2] = mesh.corners(t);
            Vec3 normal = scene::cross(p1 - p0, p2 - p0);
            float area = 0.5f * scene::length(normal);
            // Degenerate triangles stay in the list (so indices line up) with zero power.
            Triangle triangle{p0,
                              p1 - p0,
                              p2 - p0,
                              area > 0 ? normal * (0.5f / area) : Vec3{0, 0, 1},
                              mesh.material.emission,
                              area};
            m_triangles.push_back(triangle);
            double triangle_power = static_cast<double>(area) * scene::luminance(mesh.material.emission);
            power.push_back(triangle_power);
            total_power += triangle_power;
        }
    }
    if (total_power <= 0) {
        m_triangles.clear();
        return;
    }
    double running = 0;
    for (double triangle_power : power) {
        running += triangle_power;
        m_cumulative.push_back(static_cast<float>(running / total_power));
        m_select_pdf.push_back(static_cast<float>(triangle_power / total_power));
    }
    m_cumulative.back() = 1.0f;
}

LightSet::Sample LightSet::sample(float select, Sample2 point) const
{
    auto found = std::upper_bound(m_cumulative.begin(), m_cumulative.end(), select);
    std::size_t index = std::min<std::size_t>(found - m_cumulative.begin(), m_triangles.size() - 1);
    // Skip zero-power triangles that a float tie could land on.
    while (m_select_pdf[index] <= 0 && index > 0)
        --index;
    const Triangle& triangle = m_triangles[index];
    float root = std::sqrt(point.u);
    float b1 = root * (1 - point.v), b2 = root * point.v;
    Sample result;
    result.point = triangle.p0 + triangle.edge1 * b1 + triangle.edge2 * b2;
    result.normal = triangle.normal;
    result.emission = triangle.emission;
    result.area_pdf = m_select_pdf[index] / triangle.area;
    return result;
}

float LightSet::area_pdf(int mesh_index, int triangle_index) const
{
    if (m_triangles.empty() || m_first_light[mesh_index] < 0)
        return 0;
    std::size_t index = static_cast<std::size_t>(m_first_light[mesh_index] + triangle_index);
    return m_select_pdf[index] > 0 ? m_select_pdf[index] / m_triangles[index].area : 0;
}

namespace {

// The path of trace_path (start == nullptr) or trace_from_surface.
PathSample trace(const TraceContext& context, Vec3 origin, Vec3 direction, const SurfaceStart* start,
                 const PixelSampler& sampler, std::uint32_t sample_index)
{
    PathSample result;
    Vec3 throughput{1, 1, 1};
    float previous_bsdf_pdf = 0; // solid-angle density of the direction just taken
    // Light reaching the camera after `bounces` bounces goes to direct or indirect.
    auto add_light = [&result](int bounces, Vec3 radiance) {
        (bounces <= 1 ? result.direct : result.indirect) += radiance;
    };
    for (int vertex = 0;; ++vertex) {
        RayHit hit;
        const bool on_start = vertex == 0 && start != nullptr;
        if (on_start) {
            hit.mesh_index = start->mesh_index;
            hit.triangle_index = start->triangle_index;
            hit.geometric_normal = start->normal;
            origin = start->point;
            direction = -start->normal; // seen head-on from the front
        } else {
            ++result.rays;
            if (!context.rays->intersect(origin, direction, std::numeric_limits<float>::infinity(), hit))
                break;
        }
        const scene::Material& material = context.scene->meshes[hit.mesh_index].material;
        // A baked point weighs the light arriving at it, not what it reflects.
        const Vec3 albedo = on_start ? Vec3{1, 1, 1} : material.albedo;
        Vec3 point = origin + direction * hit.distance;
        float cos_front = -scene::dot(hit.geometric_normal, direction);
        bool front_side = cos_front > 0;
        Vec3 normal = front_side ? hit.geometric_normal : -hit.geometric_normal;
        if (vertex == 0) {
            result.hit = true;
            result.albedo = material.albedo;
            result.normal = normal;
            result.position = point;
            result.depth = hit.distance * scene::dot(direction, context.camera_forward);
            result.mesh_index = hit.mesh_index;
            result.triangle_index = hit.triangle_index;
            result.b1 = hit.b1;
            result.b2 = hit.b2;
        }
        if (front_side && material.is_emissive()) {
            if (vertex == 0) {
                result.emitted = material.emission;
            } else {
                float light_pdf = context.lights->area_pdf(hit.mesh_index, hit.triangle_index) *
                                  hit.distance * hit.distance / cos_front;
                add_light(vertex,
                          throughput * material.emission * power_heuristic(previous_bsdf_pdf, light_pdf));
            }
        }
        if (vertex >= context.max_depth)
            break;

        // Pairs per vertex: (light choice, roulette), light point, BSDF direction.
        std::uint32_t first_pair = 1 + 3 * static_cast<std::uint32_t>(vertex);
        Sample2 choice = sampler.get_2d(sample_index, first_pair);
        Vec3 brdf = albedo * kInversePi;
        Vec3 offset_origin = point + normal * kSurfaceOffset;

        if (!context.lights->empty()) {
            LightSet::Sample light =
                context.lights->sample(choice.u, sampler.get_2d(sample_index, first_pair + 1));
            Vec3 to_light = light.point - offset_origin;
            float distance_squared = scene::dot(to_light, to_light);
            float distance = std::sqrt(distance_squared);
            Vec3 light_direction = to_light * (1.0f / distance);
            float cos_surface = scene::dot(normal, light_direction);
            float cos_light = -scene::dot(light.normal, light_direction);
            if (cos_surface > 0 && cos_light > 0 && light.area_pdf > 0) {
                ++result.rays;
                if (!context.rays->occluded(offset_origin, light_direction, distance * (1 - 1e-3f))) {
                    float light_pdf = light.area_pdf * distance_squared / cos_light;
                    float weight = power_heuristic(light_pdf, cos_surface * kInversePi);
                    add_light(vertex + 1,
                              throughput * brdf * light.emission * (cos_surface * weight / light_pdf));
                }
            }
        }

        // Cosine sampling: brdf · cos / pdf = albedo.
        direction = sample_cosine_hemisphere(normal, sampler.get_2d(sample_index, first_pair + 2));
        previous_bsdf_pdf = std::max(scene::dot(normal, direction), 0.0f) * kInversePi;
        if (previous_bsdf_pdf <= 0)
            break;
        throughput = throughput * albedo;
        origin = offset_origin;
        if (vertex + 1 >= kRouletteStartVertex) {
            float survive = std::min(scene::max_component(throughput), 0.95f);
            if (!(choice.v < survive))
                break;
            throughput = throughput * (1.0f / survive);
        }
    }
    return result;
}

} // namespace

PathSample trace_path(const TraceContext& context, Vec3 origin, Vec3 direction, const PixelSampler& sampler,
                      std::uint32_t sample_index)
{
    return trace(context, origin, direction, nullptr, sampler, sample_index);
}

PathSample trace_from_surface(const TraceContext& context, const SurfaceStart& start, const PixelSampler& sampler,
                              std::uint32_t sample_index)
{
    return trace(context, start.point, -start.normal, &start, sampler, sample_index);
}

} // namespace modestack::render
