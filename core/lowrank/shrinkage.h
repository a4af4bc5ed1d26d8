// Optimal shrinkage of singular values (`denoise --shrink optimal`), the
// alternative to hard truncation: instead of keeping the first N modes whole and
// dropping the rest, each kept mode's singular value σ_j is replaced by
// η(σ_j), the value that minimises the expected Frobenius error of the rebuild
// under white noise (Gavish & Donoho, "Optimal shrinkage of singular values",
// IEEE Trans. Inf. Theory 2017). A mode near the noise bulk is mostly noise and
// is scaled down a lot, a strong mode hardly at all. The rebuild applies it as a
// per-mode factor η(σ_j)/σ_j on the spatial coefficients.
#pragma once

#include "core/lowrank/basis.h"

#include <cstdint>
#include <vector>

namespace modestack::lowrank {

/// The Frobenius-optimal shrinker for a singular value y in noise units
/// (y = σ / (noise_sigma · sqrt(n)), n the larger dimension) and aspect ratio
/// β = m / n ≤ 1: η(y) = sqrt((y² − β − 1)² − 4β) / y for y ≥ 1 + sqrt(β), else 0.
double optimal_shrink_frobenius(double y, double beta);

/// Factors η(σ_j)/σ_j ∈ [0, 1] for the first `rank` modes of `basis` (rows × frames
/// matrix; basis.rows must be set) with per-value noise standard deviation
/// `noise_sigma` (e.g. RankDecision::noise_sigma). All 1 when the noise is 0.
std::vector<double> optimal_shrinkage_factors(const Basis& basis, double noise_sigma, int kept_modes);

} // namespace modestack::lowrank
