// Putting re-rendered values into a denoised layer: a convex blend by the
// feathered weight times the inverse-variance share of the re-render, and the
// error estimate that goes with it. The denoised and the re-rendered values are
// independent estimates of the same pixel, so the blend's variance is
// w²·Var(rendered) + (1 − w)²·sigma²; it is least at w = sigma² / (sigma² +
// Var(rendered)), which never makes the pixel worse than either estimate: a
// re-render noisier than the denoised value (a pixel the per-pixel estimator
// choice already took well) counts for little. The renderer measures
// Var(rendered) itself (DiffIndVar = the sample variance divided by spp). The
// share is per pixel (channel means), so that a pixel's hue is blended as one.
// Pixels with weight 0 keep their values bit for bit.
#pragma once

#include <cstddef>

namespace modestack::refine {

/// The re-render's share of a pixel where its weight is 1: s / (s + r), from
/// the sums over the pixel's channels of sigma² (s) and of the rendered
/// variance (r); 1 where both are 0.
double rendered_share(double denoised_variance, double rendered_variance);

/// A channel's variance after the blend with share `share`: share²·r + (1 −
/// share)²·sigma², the two estimates independent.
inline double blended_variance(double share, double rendered_variance, double denoised_sigma)
{
    return share * share * rendered_variance +
           (1.0 - share) * (1.0 - share) * denoised_sigma * denoised_sigma;
}

/// For each of `pixels` pixels with weights[p] > 0, w = weights[p] · s / (s + r)
/// (s, r: the pixel's channel means of sigma² and rendered_variance; w =
/// weights[p] where both are 0), and each of `channels` channels:
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
