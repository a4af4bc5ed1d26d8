// `denoise --weight-smoothing` ([0060]): smooths the temporal weights pt(t, j) of
// the modes over time before the rebuild, so that the noise the weights picked
// up from the render does not make the rebuilt frames flicker.
//
// Each mode is smoothed on its own, as much as its own noise asks for:
//  - its noise level τ_j is measured on the weights themselves, robustly, from
//    the median absolute second difference (a smooth curve has second differences
//    near 0; white noise of variance τ² has 6τ²), so the higher, noisier modes get
//    the larger τ;
//  - the smoother is a Gaussian-weighted local linear fit (a straight ramp passes
//    unchanged, also at the ends of a piece), and its width is the one of
//    `widths` (or none) with the lowest SURE = ‖Sv − v‖² + 2τ² tr(S) − Fτ²;
//  - it never reaches across a jump: where two neighbouring second differences
//    are both far beyond the noise (k·√6·τ) with opposite signs, the weights are
//    cut in two pieces and each is smoothed alone, so a step in the lighting stays
//    at its frame with its full height. Segment boundaries (--segments) are never
//    crossed either: each part is a run of its own with weights of its own.
//
// Only the rebuild uses the smoothed weights B; the coefficients still come from
// the orthonormal projection on V (x̂ = B Vᵀ x, as with --train-frames). The
// smoothed weights are not re-orthonormalized: that would rescale each mode by
// how much noise its smoothing removed (putting the noise energy back) and mix
// the modes; a mode's coefficient image stays an unbiased estimate of its part.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace modestack::denoise {

/// Settings of the weight smoothing.
struct WeightSmoothingOptions {
    bool enabled = false;
    /// Gaussian widths (frames) SURE chooses from; no smoothing is always tried.
    std::vector<double> widths{0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0};
    /// k of the jump test on second differences (in units of their noise √6·τ).
    double jump_threshold = 4.0;
};

/// What was done to one mode.
struct ModeSmoothing {
    double noise = 0;          ///< τ_j, the weights' noise level
    double width = 0;          ///< chosen Gaussian width in frames (0: untouched)
    double sure_gain = 0;      ///< SURE of no smoothing minus SURE of the chosen width (≥ 0)
    std::vector<int> jumps;    ///< frames t where a new piece starts
};

/// The smoothing of every rebuilt mode (empty when off).
struct WeightSmoothingPlan {
    std::vector<ModeSmoothing> modes;
};

/// τ of `values`: 1.4826 · median |second difference| / √6 (0 for fewer than 3 values).
double weight_noise(const std::vector<double>& values);

/// Starts of pieces (ascending, > 0) where `values` jumps: see the file comment.
std::vector<int> find_weight_jumps(const std::vector<double>& values, double noise, double threshold);

/// The Gaussian local linear fit of `values` of width `width`, each piece between
/// `breaks` (ascending piece starts) on its own; `trace` receives tr(S).
/// Width 0 returns the values unchanged.
std::vector<double> smooth_pieces(const std::vector<double>& values, double width, const std::vector<int>& breaks,
                                  double* trace = nullptr);

/// Smooths each column of `weights` (F × N, the rebuild's temporal weights) as
/// described above and records what it did in `plan`.
Eigen::MatrixXd smooth_temporal_weights(const Eigen::MatrixXd& weights, const WeightSmoothingOptions& options,
                                        WeightSmoothingPlan& plan);

}  // namespace modestack::denoise
