#include "core/lowrank/gram.h"

#include "core/common/error.h"
#include "core/lowrank/tiles.h"

#include <Eigen/Core>

#include <string>

namespace modestack::lowrank {

GramAccumulator::GramAccumulator(int frames)
{
    if (frames < 1)
        throw internal_error("GramAccumulator needs at least one frame");
    m_gram = Eigen::MatrixXd::Zero(frames, frames);
    m_half_gram[0] = m_gram;
    m_half_gram[1] = m_gram;
    m_frame_sum = Eigen::VectorXd::Zero(frames);
}

void GramAccumulator::add(const BandView& band)
{
    const int frame_count = frames();
    if (band.frames != frame_count)
        throw internal_error("band has " + std::to_string(band.frames) + " frames, Gram expects " +
                             std::to_string(frame_count));
    if (band.rows <= 0)
        return;
    // One reduction, one tile order: columns [0, F) sum the even tiles, [F, 2F) the odd
    // tiles (numbered across all bands added so far), column 2F the frame sums.
    const std::int64_t first_tile = m_tiles;
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(frame_count, 2 * frame_count + 1);
    reduce_tiles_in_order(
        band.rows,
        [&](std::int64_t row0, std::int64_t count, Eigen::MatrixXd& partial) {
            Eigen::MatrixXd tile;
            copy_tile(band, row0, count, tile);
            partial.setZero(frame_count, 2 * frame_count + 1);
            const std::int64_t half = (first_tile + row0 / kTileRows) % 2;
            auto gram_part = partial.middleCols(half * frame_count, frame_count);
            // rankUpdate fills the lower triangle only; mirror it for a full matrix.
            gram_part.selfadjointView<Eigen::Lower>().rankUpdate(tile.transpose());
            gram_part.triangularView<Eigen::StrictlyUpper>() = gram_part.transpose();
            partial.col(2 * frame_count) = tile.colwise().sum().transpose();
        },
        sums);
    m_half_gram[0] += sums.leftCols(frame_count);
    m_half_gram[1] += sums.middleCols(frame_count, frame_count);
    m_gram += sums.leftCols(frame_count) + sums.middleCols(frame_count, frame_count);
    m_frame_sum += sums.col(2 * frame_count);
    m_rows += band.rows;
    m_tiles += tile_count(band.rows);
}

void GramAccumulator::merge(const GramAccumulator& other)
{
    if (other.frames() != frames())
        throw internal_error("cannot merge Gram accumulators of different frame counts");
    m_gram += other.m_gram;
    m_half_gram[0] += other.m_half_gram[0];
    m_half_gram[1] += other.m_half_gram[1];
    m_frame_sum += other.m_frame_sum;
    m_rows += other.m_rows;
    m_tiles += other.m_tiles;
}

GramAccumulator GramAccumulator::from_state(const State& state)
{
    const Eigen::Index frames = state.gram.rows();
    if (frames < 1 || state.gram.cols() != frames || state.frame_sum.size() != frames ||
        state.half_gram[0].rows() != frames || state.half_gram[0].cols() != frames ||
        state.half_gram[1].rows() != frames || state.half_gram[1].cols() != frames || state.rows < 0 ||
        state.tiles < 0)
        throw internal_error("GramAccumulator::from_state: inconsistent sizes");
    GramAccumulator accumulator(static_cast<int>(frames));
    accumulator.m_gram = state.gram;
    accumulator.m_half_gram = state.half_gram;
    accumulator.m_frame_sum = state.frame_sum;
    accumulator.m_rows = state.rows;
    accumulator.m_tiles = state.tiles;
    return accumulator;
}

} // namespace modestack::lowrank
