#include "core/lowrank/basis.h"

#include "core/common/error.h"
#include "core/lowrank/gram.h"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace modestack::lowrank {

void normalize_signs(Eigen::MatrixXd& vectors)
{
    for (Eigen::Index j = 0; j < vectors.cols(); ++j) {
        Eigen::Index largest = 0;
        for (Eigen::Index t = 1; t < vectors.rows(); ++t)
            if (std::abs(vectors(t, j)) > std::abs(vectors(largest, j)))
                largest = t;
        if (vectors.rows() > 0 && vectors(largest, j) < 0)
            vectors.col(j) = -vectors.col(j);
    }
}

Basis basis_from_gram(const Eigen::MatrixXd& gram)
{
    if (gram.rows() != gram.cols() || gram.rows() == 0)
        throw internal_error("basis_from_gram needs a non-empty square matrix");
    if (!gram.allFinite())
        throw internal_error("Gram matrix holds NaN or Inf (clean the bands before accumulating)");
    const Eigen::Index frames = gram.rows();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
    if (solver.info() != Eigen::Success)
        throw internal_error("eigen-decomposition of the Gram matrix did not converge");
    // Eigen sorts ascending; the basis wants descending.
    Basis basis;
    basis.singular_values.resize(frames);
    basis.temporal.resize(frames, frames);
    for (Eigen::Index j = 0; j < frames; ++j) {
        const Eigen::Index source = frames - 1 - j;
        basis.singular_values(j) = std::sqrt(std::max(0.0, solver.eigenvalues()(source)));
        basis.temporal.col(j) = solver.eigenvectors().col(source);
    }
    normalize_signs(basis.temporal);
    basis.frame_energy = gram.diagonal();
    basis.passes = 1;
    return basis;
}

Basis basis_from_gram(const GramAccumulator& accumulator)
{
    Basis basis = basis_from_gram(accumulator.gram());
    basis.rows = accumulator.rows();
    basis.half_gram = {accumulator.half_gram(0), accumulator.half_gram(1)};
    return basis;
}

Eigen::VectorXd leverages(const Basis& basis, int kept_modes)
{
    if (kept_modes < 0 || kept_modes > basis.modes())
        throw internal_error("leverages: rank outside the available modes");
    return basis.temporal.leftCols(kept_modes).rowwise().squaredNorm();
}

} // namespace modestack::lowrank
