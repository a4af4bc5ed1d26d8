#include "core/refine/feather.h"

#include "core/common/error.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace modestack::refine {

void validate_feather_options(const FeatherOptions& options)
{
    if (options.dilation < 0 || options.dilation > 64)
        throw usage_error("--dilate must be 0 to 64 pixels");
    if (options.feather < 0 || options.feather > 64)
        throw usage_error("--feather must be 0 to 64 pixels");
}

void feathered_weights(const std::uint8_t* selection, int width, int height, const FeatherOptions& options,
                       float* weights)
{
    validate_feather_options(options);
    const int reach = options.dilation + options.feather + 1; // beyond it the weight is 0
    const int far = reach + 1;                                // "no selected pixel within reach"
    const std::size_t pixel_count = static_cast<std::size_t>(width) * height;
    // Pass 1: horizontal distance to the nearest selected pixel of the same row.
    std::vector<int> row_distance(pixel_count, far);
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            const std::uint8_t* in = selection + static_cast<std::size_t>(y) * width;
            int* out = row_distance.data() + static_cast<std::size_t>(y) * width;
            int distance = far;
            for (int x = 0; x < width; ++x) {
                distance = in[x] ? 0 : std::min(far, distance + 1);
                out[x] = distance;
            }
            distance = far;
            for (int x = width - 1; x >= 0; --x) {
                distance = in[x] ? 0 : std::min(far, distance + 1);
                out[x] = std::min(out[x], distance);
            }
        }
    });
    // Pass 2: the exact Euclidean distance is the minimum over nearby rows of
    // (horizontal distance in that row)² + (row offset)².
    const double span = options.feather + 1.0;
    const double pi = 3.14159265358979323846;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x) {
                int best = far * far;
                for (int dy = -reach; dy <= reach; ++dy) {
                    int row = y + dy;
                    if (row < 0 || row >= height || dy * dy >= best)
                        continue;
                    int dx = row_distance[static_cast<std::size_t>(row) * width + x];
                    best = std::min(best, dx * dx + dy * dy);
                }
                double distance = std::sqrt(static_cast<double>(best));
                double weight = 0.0;
                if (distance <= options.dilation)
                    weight = 1.0;
                else if (distance < options.dilation + span)
                    weight = 0.5 * (1.0 + std::cos(pi * (distance - options.dilation) / span));
                weights[static_cast<std::size_t>(y) * width + x] = static_cast<float>(weight);
            }
    });
}

} // namespace modestack::refine
