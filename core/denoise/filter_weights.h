// The pieces the mode filter's weights are made of (mode_filter.h): Gaussian
// kernels clipped at a band's edges, the guide of a band, and a cross-bilateral
// weight w(p, q) = S_σ(|p − q|²) · exp(ρ_r · D_range(p, q) + ρ_f · D_feature(p, q)).
// The survey (one window per surveyed pixel) and the full-resolution filter
// (guided_filter.h, whole rows at a time) build every weight from the same float
// operations here, so both see the same weights.
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/confidence.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

namespace modestack::denoise {

struct FilterCandidate;

inline int kernel_radius(double width) { return width > 0 ? static_cast<int>(std::ceil(2.5 * width)) : 0; }

/// Normalised 1D Gaussian of width σ on [−radius, radius].
std::vector<double> gaussian_1d(double width);

/// Σ taps and Σ taps² over the part of a window of `radius` centred at `at` that
/// lies inside [0, length): a window's weight and noise gain where the band clips it.
void clipped_tap_sums(const std::vector<double>& taps, int radius, int at, int length, double& sum, double& squares);

/// Smooths `image` ([y][x][c] rows of the band) with the separable Gaussian of
/// `width`, clipped at the band's edges and renormalised by the clipped window's
/// weight (a box product, so still separable), and hands each smoothed row y of
/// [y0, y1) to row_done(y, values), from parallel workers.
void smooth_clipped(const float* image, const lowrank::ImageBandShape& shape, double width, int y0, int y1,
                    const std::function<void(int, const double*)>& row_done);

/// S_σ(d²) = exp(−d² / 2σ²) for every squared distance a window of σ's radius
/// holds, rounded to float.
std::vector<float> spatial_weights(double width);

/// exp(x) in float, within a few ulp of expf, for filter weights: 2^n · p(r) with
/// n = round(x / ln 2) and Cephes' degree-6 polynomial on |r| ≤ ln 2 / 2, written
/// without calls or branches so that a loop over it vectorises (the library's
/// expf is a call per weight). Below −87 it is 0, near where expf leaves the
/// normal range.
inline float weight_exp(float x)
{
    const float clamped = x < -87.0f ? -87.0f : x;
    // Round to nearest by the 1.5·2^23 shift (exact while |n| < 2^22).
    const float n = (clamped * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
    float r = clamped - n * 0.693359375f;  // Cody–Waite: ln 2 in two parts
    r = r - n * -2.12194440e-4f;
    float p = 1.9875691500e-4f;
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    p = p * (r * r) + r + 1.0f;
    const std::int32_t bits = (static_cast<std::int32_t>(n) + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    const float value = p * scale;  // computed unconditionally: a select, not a branch
    return x < -87.0f ? 0.0f : value;
}

/// The guide of a band, planar ([channel][y][x]) so that runs along x vectorise:
/// c_1 pre-smoothed (clipped and renormalised at the band's edges), the noise
/// variance of each of its samples, and the normalised feature rows, if any.
struct Guide {
    int width = 0, height = 0, channels = 0, feature_channels = 0;
    std::vector<float> value, noise, features;

    std::int64_t plane() const { return static_cast<std::int64_t>(width) * height; }
    const float* value_plane(int c) const { return value.data() + c * plane(); }
    const float* noise_plane(int c) const { return noise.data() + c * plane(); }
    const float* feature_plane(int k) const { return features.data() + k * plane(); }
};

/// The guide of `coefficients`' first image; `features` are [y][x][k] rows of
/// `feature_channels` values (null: none).
Guide build_guide(const lowrank::BandView& coefficients, const std::vector<float>& noise_variance,
                  const lowrank::ImageBandShape& shape, double smoothing, const float* features, int feature_channels);

/// A guide difference's contribution to D_range: the squared difference in units
/// of the two samples' noise.
inline float range_term(float centre, float other, float centre_noise, float other_noise)
{
    const float difference = centre - other;
    return difference * difference / (centre_noise + other_noise + 1e-30f);
}

/// A feature difference's contribution to D_feature: its square.
inline float feature_term(float centre, float other)
{
    const float difference = centre - other;
    return difference * difference;
}

/// The exponent scales of a candidate: ρ_r = −1 / (2 ρ² C) and ρ_f = −1 / (2 ρ_f² K),
/// 0 where the candidate (or the guide) has no such term.
struct ExponentScales {
    float range = 0, feature = 0;
};
ExponentScales exponent_scales(const FilterCandidate& candidate, const Guide& guide);

/// ρ_r · D_range + ρ_f · D_feature, the guided factor's exponent. A term the
/// scales lack must come in as 0: 0 · ∞ would be NaN (a range term is ∞ where the
/// guide's noise is 0).
inline float guided_exponent(ExponentScales scales, float range, float feature)
{
    return scales.range * range + scales.feature * feature;
}

/// Weights of one candidate filter around a pixel, clipped to the band: the
/// survey's per-pixel windows. The guided factor exp(ρ_r D_r + ρ_f D_f) does not
/// depend on the width, so it is computed once per pixel over the widest window
/// and shared by every width with the same scales.
class WeightWindow {
public:
    WeightWindow(const Guide& guide, int widest_radius) : m_guide(guide), m_widest(widest_radius) {}

    /// Moves to pixel (x, y).
    void centre(int x, int y);

    /// Fills the weights of `candidate` (width > 0) around the pixel; returns their sum.
    double compute(const FilterCandidate& candidate);

    /// Σ_q w_q · pixels(q, i) over the window into sums[i] for every i of
    /// `per_pixel` values: `pixels` holds the band's rows from `first_row` on as
    /// [y][x][i] (all the surveyed modes of a pixel together: one run per tap).
    void apply(const float* pixels, int first_row, int per_pixel, float* sums) const;

    std::vector<float> weights;
    std::size_t self = 0;  // the pixel's own index in `weights`
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;

private:
    const std::vector<float>& spatial(double width);
    const std::vector<float>& guided_factor(ExponentScales scales);

    const Guide& m_guide;
    int m_widest;
    int m_x = 0, m_y = 0;
    int m_wide_x0 = 0, m_wide_x1 = 0, m_wide_y0 = 0, m_wide_y1 = 0;  // the widest window, clipped
    bool m_have_distances = false;
    std::vector<float> m_range_distance, m_feature_distance;  // over the widest window
    std::vector<std::pair<double, std::vector<float>>> m_spatial_tables;
    struct Factor {
        ExponentScales scales;
        std::vector<float> values;
        bool current = false;
    };
    std::vector<Factor> m_factors;
};

}  // namespace modestack::denoise
