// Putting re-rendered values into a denoised layer: a convex blend by the
// feathered weight, and the error estimate that goes with it. The denoised and
// the re-rendered values are independent estimates of the same pixel, so the
// blend's variance is w²·Var(rendered) + (1 − w)²·sigma²; the renderer measures
// Var(rendered) itself (DiffIndVar = the sample variance divided by spp). Pixels
// with weight 0 keep their values bit for bit.
#pragma once

#include <cstddef>

namespace modestack::refine {

/// For each of `pixels` pixels with weights[p] > 0 and each of `channels` channels:
///   value ← w·rendered + (1 − w)·value,
///   sigma ← sqrt(w²·rendered_variance + (1 − w)²·sigma²).
/// Pixels with weight 0 are not touched. Arrays are interleaved pixels × channels.
void blend_refined(const float* weights, std::size_t pixels, int channels, const float* rendered,
                   const float* rendered_variance, float* value, float* sigma);

/// The relMSE the sigma channels predict: mean over pixels and channels of
/// sigma² / (value² + dark_floor²), summed in pixel order (deterministic).
double estimated_relative_mse(const float* value, const float* sigma, std::size_t pixels, int channels,
                              float dark_floor);

} // namespace modestack::refine
