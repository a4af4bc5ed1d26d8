// Per-pixel confidence of the rebuild ("35 ± 5", [0059], [0088]–[0095]): the
// estimated standard error of each rebuilt value, from the residual r = x − x̂ of
// the noisy band, pooled over a small spatial window. It catches two things: the
// noise left in the rebuild, and content the low-rank model misses (an object seen
// in a few frames only is erased by the projection, and its residual stands far
// above the noise). The refine step re-renders where sigma is high.
//
// Estimator, for pixel p, channel c, frame t, window W = (2·radius+1)² pixels around
// p clipped to the band, N modes, F frames, leverages h_t = Σ_{j≤N} V_tj², residual
// r = x − x̂:
//   d_t  = r_{q,c,t} − mean of its 4-neighbours            (spatial high-pass of r)
//   s²   = Σ_t mean_{q∈W} d_t² / (1 + 1/4) / (F − N)       (noise variance per frame)
//   μ_t  = mean_{q∈W} r_{q,c,t}                            (local mean residual)
//   τ_t² = z·s²(1 − h_t)/|W|                                (noise variance of μ_t)
//   b_t² = E[b² | μ_t, τ_t] under the row's prior            (missed content: the part of μ_t²
//                                                           noise cannot explain; bias_prior.h)
//   sigma_t = sqrt(s²·h_t + b_t²)                          (noise kept by the projection,
//                                                           Var(x̂_t) = s²·h_t, plus bias)
// Why a high-pass for s²: lighting the modes miss in every frame (a light that
// slides through the whole shot while N is too small to follow it) is smooth in
// space. Counted into s² it would look like noise the projection averages away,
// while in fact it stays in x̂ whole; the high-pass sees only white noise, so the
// missed lighting shows up in b_t where it is. It reads one row beyond the window:
// a band needs radius + 1 halo rows to give the same sigma as the whole image.
// Why the mean and not the mean square for b_t: content the modes miss (an object
// seen in a few frames) is coherent over the window, so it survives the mean,
// while noise and single-pixel fireflies (large residuals that barely move x̂)
// mostly cancel. z = 1 counts the mean's noise exactly.
// Why a learnt prior for b_t: the unbiased max(0, μ_t² − τ_t²) leaves about
// 0.48·τ_t² on a sample with no bias, far above the noise a wide mode filter
// keeps; the prior of each image row, fitted to all its frames, shrinks what
// the noise explains and keeps what it does not (bias_prior.h).
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/bias_prior.h"

#include <Eigen/Core>

#include <vector>

namespace modestack::lowrank {

/// Geometry of an image band: rows = width · height · channels, samples [y][x][c].
struct ImageBandShape {
    int width = 0;
    int height = 0;
    int channels = 0;
};

/// Knobs of the confidence estimator.
struct ConfidenceOptions {
    /// Window radius in pixels (2 → 5×5), clipped at the band edges.
    int radius = 2;
    /// z of the bias term (see the file comment): multiples of the noise variance of
    /// the windowed mean subtracted from μ_t²; 1 is unbiased.
    double bias_significance = 1.0;
};

/// D_t² (1 when `frame_scales` is empty): frame t's noise variance over the
/// whitened s² when the modes are fitted to frames of uneven noise
/// (denoise/frame_weighting.h).
inline double frame_noise_variance(const Eigen::VectorXd& frame_scales, Eigen::Index t)
{
    return frame_scales.size() == 0 ? 1.0 : frame_scales(t) * frame_scales(t);
}

/// Writes sigma for rows [valid_y0, valid_y1) of the band: `sigma` has
/// width·(valid_y1 − valid_y0)·channels rows and F frames, same interleaving. `noisy`
/// and `rebuilt` hold the whole band (with its halo rows) in `shape`; `leverages` is h
/// (length F) for `rank` modes, rank < F. Throws modestack::Error (internal) on
/// mismatched shapes. `kept_noise` (optional, valid rows × F like `sigma`) replaces
/// h_t in the noise term s²·h_t per sample: a spatial filter of the modes
/// (core/denoise/mode_filter.h) keeps less than h_t of the noise, a different amount
/// at each pixel. The residual (and so s² and the bias) still comes from `rebuilt`.
void confidence_band(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                     const Eigen::VectorXd& leverages, int kept_modes, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, MutableBandView sigma,
                     const BandView* kept_noise = nullptr);

/// The two halves of confidence_band, for a farm job whose tasks see all frames of
/// some rows (modes task) or some frames of all rows (write task), giving the same
/// bits as one call: s² of output rows [valid_y0, valid_y1) from every frame of
/// the band (float per sample, laid out like one frame of `sigma`) ...
/// With `means` (optional; frame t's output rows at means + t · means_stride, 0
/// meaning laid out like `sigma`) it also leaves there each frame's windowed
/// residual mean, the first half of frame_sigma's work, so that a whole run reads
/// every residual once and finishes with sigma_from_mean. `means` may be the
/// output rows of `noisy` itself: a frame's noisy values are all read before its
/// mean is written (a streamed band needs no other buffer for sigma). With
/// `frame_scales` D (modes fitted to frames of uneven noise,
/// denoise/frame_weighting.h) s² is that of the whitened residual r_t / D_t,
/// and frame t's noise variance is D_t² s² below ...
void residual_noise_variance(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                             int kept_modes, int valid_y0, int valid_y1, const ConfidenceOptions& options,
                             float* noise_variance, float* means = nullptr, std::int64_t means_stride = 0,
                             const Eigen::VectorXd& frame_scales = {});

/// ... the bias prior of each output row from every frame's windowed residual
/// mean (frame t's output rows at means + t · means_stride, `leverages` h_t
/// of every frame): one posterior per row, rows [valid_y0, valid_y1) ...
std::vector<BiasPosterior> row_bias_posteriors(const ImageBandShape& shape, int valid_y0, int valid_y1,
                                               const ConfidenceOptions& options, const float* noise_variance,
                                               const Eigen::VectorXd& leverages, const float* means,
                                               std::int64_t means_stride,
                                               const Eigen::VectorXd& frame_scales = {});

/// ... (its counting step: adds the bins of t² = μ²/τ² of one frame's output rows to
/// counts[y − valid_y0], for a caller that holds its frames one at a time;
/// `frame_variance` the frame's D_t²) ...
void count_bias_ratios(const ImageBandShape& shape, int valid_y0, int valid_y1,
                       const ConfidenceOptions& options, const float* noise_variance, double leverage,
                       const float* means, BiasRatioCounts* counts, double frame_variance = 1.0);

/// A further term of sigma², per output sample, times a factor of the frame:
/// the mode filter's bias of the first mode times B_t1²
/// (denoise/band_rebuild.h, first_mode_filter_bias). No values: none.
struct SigmaExtraTerm {
    const float* values = nullptr;
    double weight = 0;
};

/// ... and sigma of one frame from its noisy and rebuilt values (whole band in
/// `shape`), s², the frame's leverage h_t, or its kept noise per sample
/// (null: h_t), the output rows' posteriors and any further term, and the
/// frame's noise variance over s² (D_t², which a kept noise already holds).
/// `sigma` receives the output rows.
void frame_sigma(const float* noisy_frame, const float* rebuilt_frame, const ImageBandShape& shape,
                 int valid_y0, int valid_y1, const ConfidenceOptions& options, const float* noise_variance,
                 double leverage, const float* kept_noise, const BiasPosterior* posteriors, float* sigma,
                 SigmaExtraTerm extra = {}, double frame_variance = 1.0);

/// frame_sigma's second half: `sigma` holds the frame's windowed residual
/// mean of the output rows on entry (from residual_noise_variance) and its sigma on return.
void sigma_from_mean(const ImageBandShape& shape, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, const float* noise_variance, double leverage,
                     const float* kept_noise, const BiasPosterior* posteriors, float* sigma,
                     SigmaExtraTerm extra = {}, double frame_variance = 1.0);

} // namespace modestack::lowrank
