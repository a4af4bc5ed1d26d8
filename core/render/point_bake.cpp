// Baking indirect light at surface points (see point_bake.h).
#include "core/render/point_bake.h"

#include "core/common/error.h"
#include "core/render/path_tracer.h"
#include "core/render/ray_scene.h"
#include "core/render/sampler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

namespace modestack::render {

using scene::Vec3;

namespace {

// Keeps the points' sample streams apart from the camera pixels' of the same frame.
constexpr std::uint64_t kBakeSeedSalt = 0x626168652d707473ULL;
// Lattice points on a triangle's edges lie on the neighbouring walls too (a room's
// corners): paths started there would slip through the seam. Each point is baked
// this fraction of the way towards its triangle's centroid, off the seam.
constexpr float kInsetFraction = 1e-3f;

void bake_point(const TraceContext& context, const PointPlace& place, const RenderOptions& options, int frame,
                int x, int y, PointBake& out, std::int64_t& rays)
{
    const scene::Mesh& mesh = context.scene->meshes[place.mesh];
    auto [p0, p1, p2] = mesh.corners(static_cast<std::size_t>(place.triangle));
    Vec3 point = p0 + (p1 - p0) * place.b1 + (p2 - p0) * place.b2;
    Vec3 centroid = (p0 + p1 + p2) * (1.0f / 3.0f);
    point = point + (centroid - point) * kInsetFraction;
    float* position = out.position.at(x, y);
    position[0] = point.x, position[1] = point.y, position[2] = point.z;
    Vec3 normal = scene::cross(p1 - p0, p2 - p0);
    if (!(scene::length(normal) > 0))
        return; // a degenerate triangle receives no light
    normal = scene::normalize(normal);
    float* normal_out = out.normal.at(x, y);
    normal_out[0] = normal.x, normal_out[1] = normal.y, normal_out[2] = normal.z;
    SurfaceStart start{point, normal, place.mesh, place.triangle};
    PixelSampler sampler(mix_bits(options.seed ^ kBakeSeedSalt), frame, options.fixed_seed, x, y);
    double sum[3] = {0, 0, 0}, squares[3] = {0, 0, 0};
    for (int s = 0; s < options.spp; ++s) {
        PathSample path = trace_from_surface(context, start, sampler, static_cast<std::uint32_t>(s));
        rays += path.rays;
        const float light[3] = {path.indirect.x, path.indirect.y, path.indirect.z};
        for (int c = 0; c < 3; ++c) {
            sum[c] += light[c];
            squares[c] += static_cast<double>(light[c]) * light[c];
        }
    }
    const double n = options.spp;
    float* indirect = out.indirect.at(x, y);
    float* variance = out.variance.at(x, y);
    for (int c = 0; c < 3; ++c) {
        indirect[c] = static_cast<float>(sum[c] / n);
        variance[c] = options.spp > 1
                          ? static_cast<float>(std::max(squares[c] - sum[c] * sum[c] / n, 0.0) / (n - 1) / n)
                          : 0.0f;
    }
}

} // namespace

void point_image_size(std::int64_t count, int& width, int& height)
{
    width = static_cast<int>(std::clamp<std::int64_t>(count, 1, kPointImageWidth));
    height = static_cast<int>(std::max<std::int64_t>((count + kPointImageWidth - 1) / kPointImageWidth, 1));
}

int bake_step_count(const SurfacePoints& points)
{
    int width = 0, height = 0;
    point_image_size(points.count(), width, height);
    return (height + kBakeRowsPerStep - 1) / kBakeRowsPerStep;
}

void bake_points(const scene::Scene& scene, int frame, const SurfacePoints& points, const RenderOptions& options,
                 PointBake& out, Progress& progress)
{
    validate_render_options(options);
    points.check_topology(scene, "frame " + std::to_string(frame));
    auto start = std::chrono::steady_clock::now();
    int width = 0, height = 0;
    point_image_size(points.count(), width, height);
    out.indirect.reset(width, height, 3);
    out.variance.reset(width, height, 3);
    out.position.reset(width, height, 3);
    out.normal.reset(width, height, 3);
    out.stats = {};
    const std::vector<PointPlace>& places = points.places();
    RayScene ray_scene(scene);
    LightSet lights(scene);
    TraceContext context{&scene, &ray_scene, &lights, options.max_depth, Vec3{0, 0, -1}};
    const int steps = bake_step_count(points);
    std::vector<std::int64_t> step_rays(steps, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, steps, 1), [&](const tbb::blocked_range<int>& range) {
        for (int step = range.begin(); step != range.end(); ++step) {
            if (cancel_requested())
                return;
            int y1 = std::min((step + 1) * kBakeRowsPerStep, height);
            for (int y = step * kBakeRowsPerStep; y < y1; ++y)
                for (int x = 0; x < width; ++x) {
                    std::size_t id = static_cast<std::size_t>(y) * width + x;
                    if (id < places.size())
                        bake_point(context, places[id], options, frame, x, y, out, step_rays[step]);
                }
            progress.advance(1);
        }
    });
    for (std::int64_t rays : step_rays)
        out.stats.rays += rays;
    out.stats.paths = points.count() * options.spp;
    throw_if_cancelled();
    out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace modestack::render
