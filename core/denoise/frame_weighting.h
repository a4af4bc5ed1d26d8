// `denoise --frame-noise measured` (the default): the modes fitted to frames of
// uneven noise (docs/design.md, "Frames of uneven noise"). The SVD finds the
// modes by energy, so frames much noisier than the rest (an area light that
// switches on, a frame lit by a large source) pull modes to their noise, and
// those modes leave a fixed pattern in the clean frames. With each frame's
// noise level D_t (the root of its high-pass energy over the shot's mean,
// frame_noise.h, on the input cleaned of fireflies: the energy the Gram sums
// see. Measured as read, a glossy floor's caustic fireflies made D jump ±15 %
// from frame to frame and its layer came out 53 % worse; measured as the
// choice's mean |d|, a frame whose noise moved into fewer, brighter pixels read
// quieter at the same energy, and a light switch cost 17 %) the modes V are
// found from X D⁻¹, whose noise is even over time (what the truncated SVD, the
// rank rules and the mode filter assume), and every frame is projected with
// A = D⁻¹ V and rebuilt with B = D V: x̂ = x D⁻¹ V Vᵀ D. A noise-free shot of
// rank N still comes back exactly (X D⁻¹ keeps the rank), the coefficients
// c = x A hold noise of one level per mode, and frame t of the rebuild holds
// D_t² times the noise sigma counts in whitened units (s² of the residual
// r_t / D_t).
//
// Not with --train-frames (its projection is a least-squares fit of its own)
// nor with the randomized SVD (its passes start before the first read has
// measured D); there, and with `--frame-noise even`, D = 1.
#pragma once

#include "core/lowrank/gram.h"

#include <Eigen/Core>

#include <vector>

namespace modestack::denoise {

/// A frame's scale is at least this share of the shot's: a frame far quieter
/// than the rest (a black frame, a fade) would otherwise get an unbounded weight.
inline constexpr double kSmallestFrameScale = 0.125;

/// The frame scales D from each frame's noise factor (frame_noise.h), each at
/// least kSmallestFrameScale; empty factors give empty scales (even noise).
Eigen::VectorXd frame_scales(const std::vector<double>& noise_factors);

/// The Gram sums of X D⁻¹ (the rows' sums of each frame scaled too), from those of X.
lowrank::GramAccumulator scaled_gram(const lowrank::GramAccumulator& gram, const Eigen::VectorXd& scales);

/// D⁻¹ M (row t of `modes` over D_t): the projection; M itself when `scales` is empty.
Eigen::MatrixXd projection_weights(const Eigen::MatrixXd& modes, const Eigen::VectorXd& scales);
/// D M: the rebuild; M itself when `scales` is empty.
Eigen::MatrixXd rebuild_weights(const Eigen::MatrixXd& modes, const Eigen::VectorXd& scales);
// Frame t's noise variance over the whitened s², D_t²: lowrank::frame_noise_variance
// (core/lowrank/confidence.h), where sigma needs it too.

} // namespace modestack::denoise
