// Tiles, pixels and sample averaging (see render.h). Per pixel the samples are
// summed in double in sample order and turned into the AOVs at the end; the
// lighting layers are divided by the summed albedo so that
// Combined = DiffCol × (DiffDir + DiffInd) + Emit holds exactly (see aov.h).
#include "core/render/render.h"

#include "core/common/error.h"
#include "core/render/path_tracer.h"
#include "core/render/ray_scene.h"
#include "core/render/sampler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace modestack::render {

using scene::Vec3;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Keeps width × height × 4 floats well inside memory and int arithmetic.
constexpr long long kMaxPixels = 1LL << 28;

struct Camera {
    Vec3 position, forward, right, up;
    float tan_half_fov, aspect;
};

Camera make_camera(const scene::Camera& camera, const RenderOptions& options)
{
    Camera result;
    result.position = camera.position;
    result.forward = scene::normalize(camera.look_at - camera.position);
    result.right = scene::normalize(scene::cross(result.forward, camera.up));
    result.up = scene::cross(result.right, result.forward);
    result.tan_half_fov = static_cast<float>(std::tan(0.5 * camera.vertical_fov_degrees * kPi / 180.0));
    result.aspect = static_cast<float>(options.width) / static_cast<float>(options.height);
    return result;
}

struct Sum3 {
    double r = 0, g = 0, b = 0;
    void add(Vec3 v)
    {
        r += v.x;
        g += v.y;
        b += v.z;
    }
};

// Light divided by albedo, channel by channel; 0 where no sample saw any albedo.
float divide_or_zero(double light, double albedo)
{
    return albedo > 0 ? static_cast<float>(light / albedo) : 0.0f;
}

// Adds `weight` × the points around a sample's hit to a pixel's list of points.
void add_lookup(const SurfacePoints& points, const PathSample& path, float weight, std::vector<PointWeight>& list)
{
    PointWeight corners[3];
    points.interpolate(path.mesh_index, path.triangle_index, path.b1, path.b2, corners);
    for (const PointWeight& corner : corners) {
        if (corner.weight <= 0)
            continue;
        auto found = std::find_if(list.begin(), list.end(),
                                  [&](const PointWeight& entry) { return entry.id == corner.id; });
        if (found != list.end())
            found->weight += corner.weight * weight;
        else
            list.push_back({corner.id, corner.weight * weight});
    }
}

// The kLookupPoints heaviest points of a pixel, weights renormalised to sum to 1
// (ties broken by id, so the result does not depend on the order samples came in).
void store_lookup(std::vector<PointWeight>& list, float* lookup)
{
    std::sort(list.begin(), list.end(), [](const PointWeight& a, const PointWeight& b) {
        return a.weight != b.weight ? a.weight > b.weight : a.id < b.id;
    });
    const std::size_t kept = std::min<std::size_t>(list.size(), kLookupPoints);
    double total = 0;
    for (std::size_t k = 0; k < kept; ++k)
        total += list[k].weight;
    for (int k = 0; k < kLookupPoints; ++k) {
        bool used = static_cast<std::size_t>(k) < kept && total > 0;
        lookup[k] = used ? static_cast<float>(list[k].id) : -1.0f;
        lookup[kLookupPoints + k] = used ? static_cast<float>(list[k].weight / total) : 0.0f;
    }
}

void render_pixel(const TraceContext& context, const Camera& camera, const RenderOptions& options, int frame,
                  int x, int y, const SurfacePoints* points, FrameAovs& out, std::int64_t& rays)
{
    std::vector<PointWeight> lookup;
    PixelSampler sampler(options.seed, frame, options.fixed_seed, x, y);
    Sum3 emitted, direct, indirect, albedo, normal, position, indirect_squared;
    double depth = 0, hits = 0;
    for (int s = 0; s < options.spp; ++s) {
        auto sample_index = static_cast<std::uint32_t>(s);
        Sample2 jitter = sampler.get_2d(sample_index, 0);
        float ndc_x = (2 * (static_cast<float>(x) + jitter.u) / static_cast<float>(options.width) - 1) *
                      camera.tan_half_fov * camera.aspect;
        float ndc_y = (1 - 2 * (static_cast<float>(y) + jitter.v) / static_cast<float>(options.height)) *
                      camera.tan_half_fov;
        Vec3 direction = scene::normalize(camera.forward + camera.right * ndc_x + camera.up * ndc_y);
        PathSample path = trace_path(context, camera.position, direction, sampler, sample_index);
        rays += path.rays;
        if (!path.hit)
            continue;
        hits += 1;
        emitted.add(path.emitted);
        direct.add(path.direct);
        indirect.add(path.indirect);
        albedo.add(path.albedo);
        normal.add(path.normal);
        position.add(path.position);
        depth += path.depth;
        indirect_squared.add(path.indirect * path.indirect);
        // DiffInd weighs each sample's light by its albedo (see below): so do the points.
        if (points != nullptr)
            add_lookup(*points, path, (path.albedo.x + path.albedo.y + path.albedo.z) / 3, lookup);
    }
    if (points != nullptr)
        store_lookup(lookup, out.point_lookup.at(x, y));
    const double n = options.spp;
    auto store = [](float* pixel, const Sum3& sum, double divisor) {
        pixel[0] = static_cast<float>(sum.r / divisor);
        pixel[1] = static_cast<float>(sum.g / divisor);
        pixel[2] = static_cast<float>(sum.b / divisor);
    };
    float* beauty = out.beauty.at(x, y);
    beauty[0] = static_cast<float>((emitted.r + direct.r + indirect.r) / n);
    beauty[1] = static_cast<float>((emitted.g + direct.g + indirect.g) / n);
    beauty[2] = static_cast<float>((emitted.b + direct.b + indirect.b) / n);
    beauty[3] = static_cast<float>(hits / n);
    store(out.emission.at(x, y), emitted, n);
    store(out.albedo.at(x, y), albedo, n);
    store(out.normal.at(x, y), normal, n);
    store(out.position.at(x, y), position, n);
    out.depth.at(x, y)[0] = static_cast<float>(depth / n);
    float* direct_out = out.diffuse_direct.at(x, y);
    float* indirect_out = out.diffuse_indirect.at(x, y);
    const double albedo_sum[3] = {albedo.r, albedo.g, albedo.b};
    const double direct_sum[3] = {direct.r, direct.g, direct.b};
    const double indirect_sum[3] = {indirect.r, indirect.g, indirect.b};
    const double squared_sum[3] = {indirect_squared.r, indirect_squared.g, indirect_squared.b};
    float* variance_out = out.indirect_variance.at(x, y);
    for (int c = 0; c < 3; ++c) {
        direct_out[c] = divide_or_zero(direct_sum[c], albedo_sum[c]);
        indirect_out[c] = divide_or_zero(indirect_sum[c], albedo_sum[c]);
        // DiffInd = mean of (indirect sample / mean albedo); the variance of that
        // mean is the samples' variance / spp.
        double variance = 0;
        if (options.spp > 1 && albedo_sum[c] > 0) {
            double sample_variance = (squared_sum[c] - indirect_sum[c] * indirect_sum[c] / n) / (n - 1);
            double mean_albedo = albedo_sum[c] / n;
            variance = std::max(sample_variance, 0.0) / (mean_albedo * mean_albedo) / n;
        }
        variance_out[c] = static_cast<float>(variance);
    }
    out.rendered.at(x, y)[0] = 1.0f;
}

} // namespace

void validate_render_options(const RenderOptions& options)
{
    if (options.width < 1 || options.height < 1)
        throw usage_error("image size must be at least 1x1 (got " + std::to_string(options.width) + "x" +
                          std::to_string(options.height) + ")");
    if (static_cast<long long>(options.width) * options.height > kMaxPixels)
        throw usage_error("image size " + std::to_string(options.width) + "x" +
                          std::to_string(options.height) + " is too large");
    if (options.spp < 1)
        throw usage_error("--spp must be at least 1 (got " + std::to_string(options.spp) + ")");
    if (options.max_depth < 1)
        throw usage_error("--max-depth must be at least 1 (got " + std::to_string(options.max_depth) + ")");
}

int tile_count(const RenderOptions& options)
{
    return ((options.width + kTileSize - 1) / kTileSize) * ((options.height + kTileSize - 1) / kTileSize);
}

void render_frame(const scene::Scene& scene, int frame, const RenderOptions& options,
                  const std::uint8_t* mask, FrameAovs& out, Progress& progress, const SurfacePoints* points)
{
    validate_render_options(options);
    if (points != nullptr)
        points->check_topology(scene, "frame " + std::to_string(frame));
    auto start = std::chrono::steady_clock::now();
    out.reset(options.width, options.height, points != nullptr);
    RayScene ray_scene(scene);
    LightSet lights(scene);
    Camera camera = make_camera(scene.camera, options);
    TraceContext context{&scene, &ray_scene, &lights, options.max_depth, camera.forward};

    const int tiles_x = (options.width + kTileSize - 1) / kTileSize;
    const int tiles = tile_count(options);
    // Per-tile counters, summed in tile order afterwards (integers, but the habit stays).
    std::vector<std::int64_t> tile_paths(tiles, 0), tile_rays(tiles, 0);
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        for (int tile = range.begin(); tile != range.end(); ++tile) {
            if (cancel_requested())
                return;
            int x0 = (tile % tiles_x) * kTileSize, y0 = (tile / tiles_x) * kTileSize;
            int x1 = std::min(x0 + kTileSize, options.width), y1 = std::min(y0 + kTileSize, options.height);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    if (mask != nullptr && mask[static_cast<std::size_t>(y) * options.width + x] == 0)
                        continue;
                    render_pixel(context, camera, options, frame, x, y, points, out, tile_rays[tile]);
                    tile_paths[tile] += options.spp;
                }
            progress.advance(1);
        }
    });
    for (int tile = 0; tile < tiles; ++tile) {
        out.stats.paths += tile_paths[tile];
        out.stats.rays += tile_rays[tile];
    }
    // Tiles skipped after a cancel request leave the frame incomplete: say so.
    throw_if_cancelled();
    out.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace modestack::render
