// Error figures of an image under test x against its reference r, exactly as
// docs/design.md, "How quality is measured", defines them, so that every figure the
// project quotes is comparable: relMSE = (x - r)^2 / (r^2 + 0.01), PSNR on the
// tonemapped image (x / (1 + x))^(1/2.2) clipped to [0, 1] with peak 1, mean and
// maximum absolute error, idiff's failing/warning pixel counts (a pixel fails
// when any of its channels differs by more than the threshold), and the temporal
// flicker term ((x_t - x_{t-1}) - (r_t - r_{t-1}))^2 / (((r_t + r_{t-1}) / 2)^2 + 0.01).
// Everything is kept as sums (ErrorSums) so frames and shots merge exactly;
// sums are double and reduced in a fixed chunk order, so results are
// bit-identical for any thread count.
#pragma once

#include <cstdint>

namespace modestack::metrics {

/// The ε of relMSE and flicker: keeps dark reference pixels from dominating.
inline constexpr double kRelativeEpsilon = 0.01;
/// The display gamma of the PSNR tonemap.
inline constexpr double kPsnrGamma = 2.2;

/// idiff's per-pixel thresholds on the absolute difference |x - r|.
struct PixelThresholds {
    double fail = 1e-6; ///< a pixel fails when any channel differs by more than this
    double warn = 1e-6; ///< a pixel warns when any channel differs by more than this
};

/// Sums over the values of one or more frames; every figure is derived from them.
/// A value pair where exactly one side is NaN/Inf, or both are different
/// non-finite values, counts as an infinite error (see non_finite); a pair of
/// NaNs or of equal infinities counts as no error.
struct ErrorSums {
    std::int64_t values = 0;         ///< pixel-channel pairs compared
    std::int64_t pixels = 0;         ///< pixels compared
    double squared_relative = 0.0;   ///< Σ (x - r)^2 / (r^2 + ε)
    double squared_tonemapped = 0.0; ///< Σ (T(x) - T(r))^2, T = tonemap_for_psnr
    double absolute = 0.0;           ///< Σ |x - r|
    double max_absolute = 0.0;       ///< max |x - r| (infinite with a non-finite mismatch)
    std::int64_t pixels_failing = 0; ///< pixels with a channel over PixelThresholds::fail
    std::int64_t pixels_warning = 0; ///< pixels with a channel over PixelThresholds::warn
    std::int64_t non_finite = 0;     ///< value pairs with a NaN/Inf mismatch
    std::int64_t flicker_values = 0; ///< value pairs with a previous frame
    double flicker = 0.0;            ///< Σ flicker terms

    /// Adds `other` (order matters for bit-exact sums: merge in a fixed order).
    void merge(const ErrorSums& other);

    /// mean (x - r)^2 / (r^2 + 0.01); 0 when nothing was compared.
    double relative_mse() const;
    /// Mean squared difference of the tonemapped images; 0 when nothing was compared.
    double tonemapped_mse() const;
    /// 10 log10(1 / tonemapped_mse()) in dB; +inf for identical images.
    double psnr() const;
    /// Mean |x - r| over pixels and channels; 0 when nothing was compared.
    double mean_absolute() const;
    /// 100 × pixels_failing / pixels; 0 when nothing was compared.
    double percent_failing() const;
    /// 100 × pixels_warning / pixels; 0 when nothing was compared.
    double percent_warning() const;
    /// Mean flicker term; NaN when no value had a previous frame (a shot's first frame).
    double mean_flicker() const;
};

/// The PSNR tonemap: (v / (1 + v))^(1/2.2), clipped to [0, 1] (v <= 0 gives 0,
/// +inf gives 1). NaN stays NaN.
double tonemap_for_psnr(double value);

/// Per-frame sums of `test` against `reference`: `pixel_count` pixels of
/// `channels` interleaved floats each (value c of pixel p at [p * channels + c]).
/// Flicker fields are left at zero (see add_flicker). Parallel over fixed
/// chunks of pixels with a chunk-ordered reduction: the result does not depend
/// on the number of threads.
ErrorSums frame_errors(const float* test, const float* reference, std::int64_t pixel_count, int channels,
                       const PixelThresholds& thresholds);

/// Adds the flicker terms of frame t against frame t-1 to `sums`, for
/// `value_count` interleaved values of each buffer (same layout as frame_errors).
void add_flicker(const float* test, const float* reference, const float* previous_test,
                 const float* previous_reference, std::int64_t value_count, ErrorSums& sums);

} // namespace modestack::metrics
