#include "core/lowrank/randomized_svd.h"

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/lowrank/tiles.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace modestack::lowrank {
namespace {

// A uniform number in the open interval (0, 1) from 53 random bits.
double open_unit(std::mt19937_64& engine)
{
    return (static_cast<double>(engine() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Orthonormal basis of the columns of `matrix` (Householder QR, thin Q).
Eigen::MatrixXd orthonormalize(const Eigen::MatrixXd& matrix)
{
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(matrix);
    return qr.householderQ() * Eigen::MatrixXd::Identity(matrix.rows(), matrix.cols());
}

struct PassResult {
    Eigen::MatrixXd product; // Xᵀ X Q, F × columns
    Eigen::VectorXd frame_energy;
    std::int64_t rows = 0;
};

// One pass over the bands: Z = Xᵀ(X Q) and diag(XᵀX), summed tile by tile.
PassResult apply_gram(const BandPass& pass, int frames, const Eigen::MatrixXd& q)
{
    const Eigen::Index columns = q.cols();
    // Column `columns` of the running sum carries the frame energies.
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(frames, columns + 1);
    PassResult result;
    pass([&](const BandView& band) {
        if (band.frames != frames)
            throw internal_error("band has " + std::to_string(band.frames) +
                                 " frames, randomized SVD expects " + std::to_string(frames));
        if (band.rows <= 0)
            return;
        reduce_tiles_in_order(
            band.rows,
            [&](std::int64_t row0, std::int64_t count, Eigen::MatrixXd& partial) {
                Eigen::MatrixXd tile;
                copy_tile(band, row0, count, tile);
                const Eigen::MatrixXd projected = tile * q; // count × columns
                partial.resize(frames, columns + 1);
                partial.leftCols(columns).noalias() = tile.transpose() * projected;
                partial.col(columns) = tile.colwise().squaredNorm().transpose();
            },
            sums);
        result.rows += band.rows;
    });
    result.product = sums.leftCols(columns);
    result.frame_energy = sums.col(columns);
    return result;
}

} // namespace

Eigen::MatrixXd gaussian_matrix(int rows, int columns, std::uint64_t seed)
{
    std::mt19937_64 engine(seed);
    Eigen::MatrixXd matrix(rows, columns);
    double* values = matrix.data();
    const Eigen::Index count = matrix.size();
    constexpr double kTwoPi = 6.283185307179586476925286766559;
    for (Eigen::Index i = 0; i < count; i += 2) {
        const double radius = std::sqrt(-2.0 * std::log(open_unit(engine)));
        const double angle = kTwoPi * open_unit(engine);
        values[i] = radius * std::cos(angle);
        if (i + 1 < count)
            values[i + 1] = radius * std::sin(angle);
    }
    return matrix;
}

Basis randomized_svd(const BandPass& pass, int frames, int kept_modes, const RandomizedSvdOptions& options,
                     Progress& progress)
{
    if (frames < 1)
        throw internal_error("randomized SVD needs at least one frame");
    if (kept_modes < 1 || kept_modes > frames)
        throw usage_error("rank " + std::to_string(kept_modes) + " is outside 1.." + std::to_string(frames) +
                          " (the number of frames)");
    if (options.oversampling < 0 || options.power_iterations < 0)
        throw usage_error("randomized SVD oversampling and power iterations must not be negative");
    const int columns = std::min(frames, kept_modes + options.oversampling);
    const int total_passes = options.power_iterations + 2;
    progress.begin("randomized SVD", total_passes);

    // Range finder: Q spans (XᵀX)^(q+1) Ω; orthonormalizing after every pass keeps
    // the small modes from drowning in rounding error.
    PassResult first = apply_gram(pass, frames, gaussian_matrix(frames, columns, options.seed));
    progress.advance();
    Eigen::MatrixXd q = orthonormalize(first.product);
    for (int iteration = 0; iteration < options.power_iterations; ++iteration) {
        q = orthonormalize(apply_gram(pass, frames, q).product);
        progress.advance();
    }
    // Rayleigh–Ritz: eigen-decompose Qᵀ XᵀX Q; its eigenvalues are σ² and Q·U the modes.
    const PassResult last = apply_gram(pass, frames, q);
    progress.advance();
    Eigen::MatrixXd small = q.transpose() * last.product;
    small = 0.5 * (small + small.transpose()).eval();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(small);
    if (solver.info() != Eigen::Success)
        throw internal_error("randomized SVD: small eigenproblem did not converge");

    Basis basis;
    basis.singular_values.resize(kept_modes);
    basis.temporal.resize(frames, kept_modes);
    for (int j = 0; j < kept_modes; ++j) {
        const Eigen::Index source = columns - 1 - j; // Eigen sorts ascending
        basis.singular_values(j) = std::sqrt(std::max(0.0, solver.eigenvalues()(source)));
        basis.temporal.col(j) = q * solver.eigenvectors().col(source);
    }
    normalize_signs(basis.temporal);
    basis.frame_energy = first.frame_energy;
    basis.rows = first.rows;
    basis.passes = total_passes;
    progress.end();
    return basis;
}

} // namespace modestack::lowrank
