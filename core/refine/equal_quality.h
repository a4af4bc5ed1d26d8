// The project's quality figures (docs/design.md, "How quality is measured") as plain
// functions, for `modestack run --reference-spp`: relMSE, the noise constant c of
// relMSE(s) = c / s fitted on a noisy render, the equivalent spp of a result, and
// the renderer's time model t(s) = t0 + k·s for the equal-quality speed-up.
#pragma once

#include <cstddef>

namespace modestack::refine {

/// Mean over `count` values of (x − r)² / (r² + 0.01).
double relative_mse(const float* x, const float* reference, std::size_t count);

/// c of relMSE(s) = c / s from one noisy render at `spp` measured against a
/// reference at `reference_spp` samples with independent noise: the measured
/// error is c/spp + c/reference_spp.
double noise_constant(double noisy_relative_mse, double spp, double reference_spp);

/// The spp a brute-force render needs for the error of a result measured as
/// `relative_mse` against the same reference: c / (e − c/K). +infinity when the
/// error is at or below the reference's own (not measurable).
double equivalent_spp(double relative_mse, double c, double reference_spp);

/// Render time per frame as t(s) = t0 + k·s.
struct TimeModel {
    double t0 = 0; ///< seconds per frame at 0 spp (scene build, BVH, writing), ≥ 0
    double k = 0;  ///< seconds per frame per spp
    double seconds(double spp) const { return t0 + k * spp; }
};

/// The line through two measured (spp, seconds per frame) points, t0 clamped at 0.
TimeModel fit_time_model(double spp_a, double seconds_a, double spp_b, double seconds_b);

} // namespace modestack::refine
