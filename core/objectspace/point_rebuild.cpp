// Pixels from the surface points their PointLookup names (see point_rebuild.h).
#include "core/objectspace/point_rebuild.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::objectspace {

void rebuild_from_points(const float* lookup, std::size_t pixels, const float* point_values,
                         const float* point_sigma, int channels, std::int64_t point_count, const std::string& file,
                         float* rebuilt, float* sigma)
{
    const std::size_t ch = static_cast<std::size_t>(channels);
    for (std::size_t p = 0; p < pixels; ++p) {
        const float* entry = lookup + p * kLookupChannels;
        double value[4] = {0, 0, 0, 0}, error[4] = {0, 0, 0, 0};
        std::fill(rebuilt + p * ch, rebuilt + (p + 1) * ch, 0.0f);
        std::fill(sigma + p * ch, sigma + (p + 1) * ch, 0.0f);
        for (int k = 0; k < render::kLookupPoints; ++k) {
            const float weight = entry[render::kLookupPoints + k];
            if (!(weight > 0))
                continue;
            const float id = entry[k];
            if (!(id >= 0 && id < static_cast<float>(point_count)))
                throw bad_input(file, fmt::format("PointLookup names point {} of pixel {}, but the points sequence "
                                                  "has {} points",
                                                  id, p, point_count));
            const std::size_t point = static_cast<std::size_t>(id);
            for (std::size_t c = 0; c < ch && c < 4; ++c) {
                value[c] += static_cast<double>(weight) * point_values[point * ch + c];
                error[c] += static_cast<double>(weight) * point_sigma[point * ch + c];
            }
        }
        for (std::size_t c = 0; c < ch && c < 4; ++c) {
            rebuilt[p * ch + c] = static_cast<float>(value[c]);
            sigma[p * ch + c] = static_cast<float>(error[c]);
        }
    }
}

} // namespace modestack::objectspace
