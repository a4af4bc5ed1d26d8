// The temporal basis of a shot: singular values σ_j of X and its right singular
// vectors (the temporal modes pt(t, j) of the patent, [0046]–[0048]), plus the
// per-frame energies that the rank rules need. It comes either from the exact
// Gram route (basis_from_gram) or from the randomized SVD (top modes only). A
// fixed sign convention makes every mode, and so every report, reproducible.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace modestack::lowrank {

class GramAccumulator;

/// Singular values and temporal modes of X (P rows × F frames).
struct Basis {
    /// σ_j = sqrt(eigenvalue j of XᵀX), descending, K values (K = F on the Gram route).
    Eigen::VectorXd singular_values;
    /// V: F×K, orthonormal columns; column j is temporal mode j. Sign convention: the
    /// entry of largest magnitude (first one on ties) is positive.
    Eigen::MatrixXd temporal;
    /// diag(XᵀX): Σ_i x_it² per frame t (length F). With singular_values it gives the
    /// energy left outside the available modes, even when K < F.
    Eigen::VectorXd frame_energy;
    /// Number of rows P of X (0 when unknown, e.g. a basis made from a bare matrix).
    std::int64_t rows = 0;
    /// Passes over the data that produced this basis (1 for the Gram route).
    int passes = 0;
    /// XᵀX of two interleaved halves of the rows (GramAccumulator::half_gram), for the
    /// cross-fitted PRESS rule; empty matrices when not known (randomized SVD).
    std::array<Eigen::MatrixXd, 2> half_gram;

    /// Number of frames F.
    int frames() const { return static_cast<int>(temporal.rows()); }
    /// Number of available modes K.
    int modes() const { return static_cast<int>(singular_values.size()); }
};

/// Eigen-decomposition of a symmetric Gram matrix XᵀX (F×F) into a full basis
/// (K = F): eigenvalues sorted descending, negative ones (rounding) clamped to 0.
/// `rows` is left 0.
Basis basis_from_gram(const Eigen::MatrixXd& gram);
/// The same from an accumulator, with `rows` and `half_gram` filled in.
Basis basis_from_gram(const GramAccumulator& accumulator);

/// Flips the sign of each column of `vectors` so that its entry of largest
/// magnitude is positive (the convention of Basis::temporal).
void normalize_signs(Eigen::MatrixXd& vectors);

/// Leverages h_t = Σ_{j<rank} V_tj² of the rank-`rank` projection (length F): the
/// diagonal of the hat matrix V_N V_Nᵀ.
Eigen::VectorXd leverages(const Basis& basis, int kept_modes);

} // namespace modestack::lowrank
