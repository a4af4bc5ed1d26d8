#include "core/denoise/frame_weighting.h"

#include "core/common/error.h"

#include <algorithm>

namespace modestack::denoise {

Eigen::VectorXd frame_scales(const std::vector<double>& noise_factors)
{
    Eigen::VectorXd scales(static_cast<Eigen::Index>(noise_factors.size()));
    for (size_t t = 0; t < noise_factors.size(); ++t)
        scales[static_cast<Eigen::Index>(t)] = std::max(noise_factors[t], kSmallestFrameScale);
    return scales;
}

lowrank::GramAccumulator scaled_gram(const lowrank::GramAccumulator& gram, const Eigen::VectorXd& scales)
{
    if (scales.size() == 0)
        return gram;
    if (scales.size() != gram.frames())
        throw internal_error("scaled_gram: a scale per frame is needed");
    const Eigen::VectorXd inverse = scales.cwiseInverse();
    lowrank::GramAccumulator::State state = gram.state();
    state.gram = inverse.asDiagonal() * state.gram * inverse.asDiagonal();
    for (Eigen::MatrixXd& half : state.half_gram)
        half = inverse.asDiagonal() * half * inverse.asDiagonal();
    state.frame_sum = state.frame_sum.cwiseProduct(inverse);
    return lowrank::GramAccumulator::from_state(state);
}

Eigen::MatrixXd projection_weights(const Eigen::MatrixXd& modes, const Eigen::VectorXd& scales)
{
    if (scales.size() == 0)
        return modes;
    return scales.cwiseInverse().asDiagonal() * modes;
}

Eigen::MatrixXd rebuild_weights(const Eigen::MatrixXd& modes, const Eigen::VectorXd& scales)
{
    if (scales.size() == 0)
        return modes;
    return scales.asDiagonal() * modes;
}

} // namespace modestack::denoise
