// `denoise --whiten`: noise whitening with the renderer's variance layer. The SVD
// picks modes by energy, and render noise is far from uniform: bright, noisy
// regions (a lit wall next to the light, caustic-like paths) hold most of the
// noise energy, so the noise modes the rank rule and the mode filter must reject
// are mostly theirs, and the quiet regions get modes fitted to someone else's
// noise. Scaling every sample by 1/standard deviation of its noise before the
// SVD makes the noise the same everywhere (white), which is what the truncated
// SVD, the rank rules and Gavish–Donoho assume; the rebuild is scaled back after.
//
// The variance layer holds, per frame, the variance of each pixel's mean
// (our renderer's `DiffIndVar`), itself a noisy estimate from a few samples. The
// weight of a sample uses its mean over every frame of the shot, pooled over a
// 3 × 3 window, floored at `floor_fraction` × the shot's mean variance (a pixel
// without noise would otherwise get an unbounded weight):
//   w(p, c) = 1 / sqrt(max(v̄(p, c), floor)), scaled so that the mean w is 1.
// The weights are one per sample row of X, constant over time, and they enter
// the modes only: the engine accumulates the Gram matrix (or runs the randomized
// SVD) on W X, whose temporal modes V are fitted to white noise, and projects and
// rebuilds the rows as read, X V Vᵀ — the same as W⁻¹ (W X) V Vᵀ, since a row
// scaling commutes with the projection. The mode filter and sigma therefore keep
// working on the unweighted coefficients: filtering in the weighted domain and
// dividing back afterwards mixes pixels of different weights (measured: relMSE
// 0.0051 → 0.0096 on the switch scene). A noise-free shot of rank N comes back
// exactly (W X has the row space of X).
#pragma once

#include "core/denoise/frame_stream.h"

#include <vector>

namespace modestack::denoise {

/// Settings of the whitening weights.
struct WhiteningOptions {
    double floor_fraction = 1e-3;  ///< variance floor, times the shot's mean variance
    int pool_radius = 1;           ///< spatial pooling of the mean variance (pixels)
};

/// The weights and what they are made of, for the JSON summary.
struct WhiteningWeights {
    std::vector<float> weights;  ///< w per sample, [row][x][channel] of the whole image
    double mean_variance = 0;    ///< shot mean of the variance layer
    double floor = 0;            ///< the variance floor used
    double smallest = 0;         ///< smallest and largest w
    double largest = 0;
    std::int64_t floored_samples = 0;  ///< samples whose mean variance was below the floor
};

/// Reads the variance layer of every frame of `source` (frame after frame) and
/// computes the weights. Throws an internal error when the source has no
/// variance channels, a bad-input error naming the layer when a variance is
/// negative or not finite.
WhiteningWeights whitening_weights(FrameSource& source, const WhiteningOptions& options = {});

/// The weights of layer `layer` (of `channels` channels) when the layers are
/// denoised apart, from its own variance alone (source.layer_variance_channels):
/// whitening_weights of a shot of that layer's channels, so the same bits as a
/// run of the layer alone (its own mean variance, floor and normalisation, not
/// those of every layer together). Errors as whitening_weights.
WhiteningWeights layer_whitening_weights(FrameSource& source, int layer, int channels,
                                         const WhiteningOptions& options = {});

}  // namespace modestack::denoise
