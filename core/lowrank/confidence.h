// Per-pixel confidence of the rebuild ("35 ± 5", [0059], [0088]–[0095]): the
// estimated standard error of each rebuilt value, from the residual r = x − x̂ of
// the noisy band, pooled over a small spatial window. It catches two things: the
// noise left in the rebuild, and content the low-rank model misses (an object seen
// in a few frames only is erased by the projection, and its residual stands far
// above the noise). The refine step re-renders where sigma is high.
//
// Estimator, for pixel p, channel c, frame t, window W = (2·radius+1)² pixels around
// p clipped to the band, N modes, F frames, leverages h_t = Σ_{j≤N} V_tj²:
//   m_t  = mean_{q∈W} r_{q,c,t}²                        (windowed residual power)
//   s²   = Σ_t m_t / (F − N)                             (noise variance: residual energy
//                                                         over F − N degrees of freedom)
//   b_t² = max(0, m_t − s²(1 − h_t)·(1 + z·sqrt(2/|W|))) (model bias: residual power beyond
//                                                         what noise explains)
//   sigma_t = sqrt(s²·h_t + b_t²)                        (noise kept by the projection,
//                                                         h_t = Var(x̂_t)/s², plus bias)
// z (bias_significance) discounts the chance excess of m_t over its expectation
// s²(1 − h_t): m_t averages |W| squared residuals, so its relative spread under pure
// noise is sqrt(2/|W|). With z = 0 (the plain formula) that chance excess alone
// (≈ 0.11·s² for a 5×5 window) outweighs the real error s²·h_t ≈ s²·N/F and sigma
// overstates the error everywhere; see tests/lowrank/test_confidence.cpp.
#pragma once

#include "core/lowrank/band.h"

#include <Eigen/Core>

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
    /// z of the bias term (see the file comment); 0 gives the plain formula.
    double bias_significance = 3.0;
};

/// Writes sigma for rows [valid_y0, valid_y1) of the band: `sigma` has
/// width·(valid_y1 − valid_y0)·channels rows and F frames, same interleaving. `noisy`
/// and `rebuilt` hold the whole band (with its halo rows) in `shape`; `leverages` is h
/// (length F) for `rank` modes, rank < F. Throws modestack::Error (internal) on
/// mismatched shapes.
void confidence_band(const BandView& noisy, const BandView& rebuilt, const ImageBandShape& shape,
                     const Eigen::VectorXd& leverages, int rank, int valid_y0, int valid_y1,
                     const ConfidenceOptions& options, MutableBandView sigma);

} // namespace modestack::lowrank
