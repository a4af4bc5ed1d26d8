// Rebuilding a frame's pixels from the denoised surface points: each pixel's
// PointLookup (core/render/aov.h) names up to kLookupPoints points and their
// weights, which sum to 1, and the pixel is their weighted sum. Sigma adds the
// same way, not in quadrature: the points' errors are correlated, so they add
// linearly.
#pragma once

#include "core/render/aov.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace modestack::objectspace {

/// Channels of one pixel's PointLookup: kLookupPoints ids, then their weights.
inline constexpr int kLookupChannels = 2 * render::kLookupPoints;

/// Rebuilds `pixels` pixels of a frame from `lookup` (PointLookup: kLookupPoints
/// ids then as many weights per pixel): rebuilt = Σ w·value, sigma = Σ w·sigma,
/// in double, for up to 4 channels per point and pixel (`channels`; any further
/// channel is 0). Slots without a positive weight are skipped. Throws a bad-input
/// error naming `file` for an id that is not below `point_count`.
void rebuild_from_points(const float* lookup, std::size_t pixels, const float* point_values,
                         const float* point_sigma, int channels, std::int64_t point_count, const std::string& file,
                         float* rebuilt, float* sigma);

} // namespace modestack::objectspace
