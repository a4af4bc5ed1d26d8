#include "core/denoise/training.h"

#include "core/common/error.h"
#include "core/denoise/engine.h"

#include "core/lowrank/tiles.h"
#include <fmt/format.h>

namespace modestack::denoise {
namespace {

// Σ⁻¹ for the first `modes` singular values; 0 for a zero value (no such mode).
Eigen::VectorXd inverse_values(const lowrank::Basis& basis, int modes)
{
    Eigen::VectorXd inverse(modes);
    for (int j = 0; j < modes; ++j)
        inverse[j] = basis.singular_values[j] > 0 ? 1.0 / basis.singular_values[j] : 0.0;
    return inverse;
}

} // namespace

TrainingGram::TrainingGram(int frames, std::vector<int> training)
    : m_frames(frames), m_training(std::move(training)),
      m_cross(Eigen::MatrixXd::Zero(frames, m_training.size()))
{
    if (m_training.size() < 3)
        throw internal_error("training frames: at least 3 are needed");
    for (size_t k = 0; k < m_training.size(); ++k)
        if (m_training[k] < 0 || m_training[k] >= frames || (k > 0 && m_training[k] <= m_training[k - 1]))
            throw internal_error("training frames must be ascending frame indices");
}

void TrainingGram::add(const lowrank::BandView& chunk)
{
    if (chunk.frames != m_frames)
        throw internal_error("training Gram: chunk with the wrong number of frames");
    const int count = static_cast<int>(m_training.size());
    lowrank::reduce_tiles_in_order(
        chunk.rows,
        [&](std::int64_t row0, std::int64_t rows, Eigen::MatrixXd& partial) {
            Eigen::MatrixXd tile;
            lowrank::copy_tile(chunk, row0, rows, tile);
            Eigen::MatrixXd training(rows, count);
            for (int k = 0; k < count; ++k)
                training.col(k) = tile.col(m_training[static_cast<size_t>(k)]);
            partial.noalias() = tile.transpose() * training;
        },
        m_cross);
    m_rows += chunk.rows;
}

lowrank::Basis TrainingGram::basis() const
{
    const int count = static_cast<int>(m_training.size());
    Eigen::MatrixXd gram(count, count);
    for (int k = 0; k < count; ++k)
        gram.row(k) = m_cross.row(m_training[static_cast<size_t>(k)]);
    lowrank::Basis basis = lowrank::basis_from_gram(0.5 * (gram + gram.transpose()));
    basis.rows = m_rows;
    basis.passes = 1;
    return basis;
}

Eigen::MatrixXd TrainingGram::projector(const lowrank::Basis& basis, int modes) const
{
    Eigen::MatrixXd projector = Eigen::MatrixXd::Zero(m_frames, modes);
    const Eigen::VectorXd inverse = inverse_values(basis, modes);
    for (size_t k = 0; k < m_training.size(); ++k)
        projector.row(m_training[k]) =
            basis.temporal.row(static_cast<Eigen::Index>(k)).head(modes).cwiseProduct(inverse.transpose());
    return projector;
}

Eigen::MatrixXd TrainingGram::weights(const lowrank::Basis& basis, int modes) const
{
    return m_cross * basis.temporal.leftCols(modes) * inverse_values(basis, modes).asDiagonal();
}

Eigen::MatrixXd TrainingGram::temporal_modes(const lowrank::Basis& basis, int modes) const
{
    const Eigen::VectorXd inverse = inverse_values(basis, modes);
    return weights(basis, modes) * inverse.asDiagonal();
}

void check_training_frames(const Settings& settings, int frames)
{
    const std::vector<int>& training = settings.training_frames;
    const int count = static_cast<int>(training.size());
    if (count < 3)
        throw usage_error(fmt::format("--train-frames gives {} frames: at least 3 are needed", count));
    for (int k = 0; k < count; ++k)
        if (training[k] < 0 || training[k] >= frames || (k > 0 && training[k] <= training[k - 1]))
            throw usage_error("--train-frames: the frames must be frames of the shot, in ascending order");
    if (settings.rank_rule.rule == lowrank::RankRule::Fixed && settings.rank_rule.fixed_modes >= count)
        throw usage_error(fmt::format("--rank {} needs more than {} training frames (--train-frames)",
                                      settings.rank_rule.fixed_modes, count));
    if (settings.mode_filter.enabled)
        throw usage_error("--train-frames needs --no-mode-filter");
    if (settings.solver == Solver::RandomizedSvd)
        throw usage_error("--train-frames needs the gram solver (--method gram or auto)");
}

Eigen::VectorXd training_leverages(const Eigen::MatrixXd& projector, const Eigen::MatrixXd& weights)
{
    return projector.cwiseProduct(weights).rowwise().sum();
}

} // namespace modestack::denoise
