// `denoise --train-frames RANGE` ([0043]): the temporal basis is computed from a
// subset of the frames (e.g. every 4th) and every frame is projected on it. Pass 1
// accumulates the cross-Gram matrix C = Xᵀ X_T (F × F_T, T the training frames)
// instead of the full F × F Gram matrix, which costs F_T / F of its products;
// the modes V_T, Σ come from the training block C_TT = X_Tᵀ X_T. The spatial modes
// are U = X_T V_T Σ⁻¹, and frame t is rebuilt by its least-squares fit on them:
// x̂_t = U Uᵀ x_t. Per sample row x (over frames) that is x̂ = B Aᵀ x with
// A = V_T Σ⁻¹ placed in the training rows (zeros elsewhere) and B = C V_T Σ⁻¹, so
// the engine's project/rebuild steps apply unchanged with A for the projection
// and B for the rebuild. On the training frames this is exactly the usual
// rank-N projection; a frame outside them does not see its own noise through the
// modes (its leverage A_t·B_t is 0).
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/basis.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace modestack::denoise {

/// Pass 1 of a run with training frames.
class TrainingGram {
public:
    /// `training`: ascending frame indices in [0, frames), at least 3.
    TrainingGram(int frames, std::vector<int> training);
    /// Adds a chunk of X (all frames; free of NaN/Inf). Fixed tiles, in order.
    void add(const lowrank::BandView& chunk);
    /// The basis of the training frames (rows set; no half Gram matrices, so the
    /// press rule is the plain, not the cross-fitted, PRESS).
    lowrank::Basis basis() const;
    /// A (F × modes): the projection onto the spatial modes.
    Eigen::MatrixXd projector(const lowrank::Basis& basis, int modes) const;
    /// B (F × modes): the rebuild's temporal weights, B = C V_T Σ⁻¹.
    Eigen::MatrixXd weights(const lowrank::Basis& basis, int modes) const;
    /// B Σ⁻¹ = C V_T Σ⁻² (F × modes): the temporal modes over every frame (V_T on
    /// the training frames), for the report.
    Eigen::MatrixXd temporal_modes(const lowrank::Basis& basis, int modes) const;
    const std::vector<int>& training() const { return m_training; }

private:
    int m_frames;
    std::vector<int> m_training;
    Eigen::MatrixXd m_cross; // C = Xᵀ X_T
    std::int64_t m_rows = 0;
};

/// Checks settings.training_frames for a shot of `frames` frames: at least 3,
/// ascending, in range, a fixed rank below their count, the Gram solver and no
/// mode filter. Throws usage errors naming --train-frames.
struct Settings;
void check_training_frames(const Settings& settings, int frames);

/// diag(B Aᵀ): the leverage of each frame in the rebuild x̂ = B Aᵀ x (sigma).
Eigen::VectorXd training_leverages(const Eigen::MatrixXd& projector, const Eigen::MatrixXd& weights);

} // namespace modestack::denoise
