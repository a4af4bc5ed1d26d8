// Randomized SVD (Halko, Martinsson & Tropp 2011, subspace iteration) for the top
// temporal modes of a long shot, without forming XᵀX and without storing anything
// with one entry per pixel: each pass over the bands accumulates Z = Xᵀ(X Q) for a
// thin F×(k+p) matrix Q, in double over fixed row tiles combined in tile order (as
// the Gram accumulator does), so results are bit-identical for any thread count.
// The Gaussian start matrix comes from std::mt19937_64 and our own Box–Muller, so it
// is the same on every platform (std::normal_distribution is not).
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/basis.h"

#include <Eigen/Core>

#include <cstdint>

namespace modestack {
class Progress;
}

namespace modestack::lowrank {

/// Knobs of the randomized SVD.
struct RandomizedSvdOptions {
    /// Extra columns p beyond the wanted rank k (HMT recommend 5–10).
    int oversampling = 10;
    /// Power iterations q: each costs one more pass and sharpens the spectrum gap.
    int power_iterations = 2;
    /// Seed of the Gaussian start matrix.
    std::uint64_t seed = 1;
};

/// Top-`rank` singular values and temporal modes of the matrix that `pass` visits
/// (F = `frames` columns). Makes power_iterations + 2 passes (reported in
/// Basis::passes); fills frame_energy and rows during the first pass. When
/// rank + oversampling ≥ F the subspace is all of R^F and the result is exact.
/// Throws modestack::Error (usage) for rank < 1 or rank > frames, (internal) for
/// inconsistent bands, and stops with an Error when a cancel was requested.
/// Progress gets one unit per pass.
Basis randomized_svd(const BandPass& pass, int frames, int kept_modes, const RandomizedSvdOptions& options,
                     Progress& progress);

/// An F×columns matrix of standard normal numbers, reproducible from `seed` on
/// every platform (mt19937_64 + Box–Muller), filled column by column.
Eigen::MatrixXd gaussian_matrix(int rows, int columns, std::uint64_t seed);

} // namespace modestack::lowrank
