// Accumulation of the F×F Gram matrix XᵀX of the data matrix, band by band: the
// exact route to the temporal modes (their eigenvectors) when F is small enough
// for an F×F eigenproblem. Memory is O(F²) whatever the number of pixels. Sums are
// in double over fixed row tiles combined in tile order, so the result is
// bit-identical for any thread count; two accumulators merge in a fixed order, so a
// farm that splits a shot into fixed pieces gets reproducible results too.
#pragma once

#include "core/lowrank/band.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace modestack::lowrank {

/// Running XᵀX and per-frame energies over the bands seen so far.
class GramAccumulator {
public:
    /// An empty accumulator for `frames` columns (frames ≥ 1).
    explicit GramAccumulator(int frames);

    /// Adds band.rows rows of X. The band must be free of NaN/Inf (see outliers.h)
    /// and have band.frames == frames(); throws modestack::Error (internal) otherwise,
    /// and when a cancel was requested.
    void add(const BandView& band);
    /// Adds another accumulator's sums (same frame count) to this one. The result of
    /// a.merge(b) is reproducible but may differ in the last bits from adding all bands
    /// to one accumulator; merge always in the same order.
    void merge(const GramAccumulator& other);

    /// XᵀX (frames × frames, symmetric).
    const Eigen::MatrixXd& gram() const { return m_gram; }
    /// Per-frame energy Σ_i x_it² (the diagonal of XᵀX).
    Eigen::VectorXd frame_energy() const { return m_gram.diagonal(); }
    /// XᵀX over one of two interleaved halves of the rows (`half` 0 or 1): the row tiles
    /// numbered across all bands, even tiles in half 0, odd in half 1. Their noise is
    /// independent, which the cross-fitted PRESS rank rule uses (rank_rule.h).
    const Eigen::MatrixXd& half_gram(int half) const { return m_half_gram[half]; }
    /// Per-frame sum Σ_i x_it (for means and reports).
    const Eigen::VectorXd& frame_sum() const { return m_frame_sum; }
    /// Number of rows (samples) added so far: P of the noise-floor rule.
    std::int64_t rows() const { return m_rows; }
    /// Number of frames F.
    int frames() const { return static_cast<int>(m_gram.rows()); }

    /// Everything the accumulator holds, for the farm's stage files (io/stage_files.h).
    /// The matrices are exactly symmetric, so their lower triangles carry them.
    struct State {
        Eigen::MatrixXd gram;
        std::array<Eigen::MatrixXd, 2> half_gram;
        Eigen::VectorXd frame_sum;
        std::int64_t rows = 0;
        std::int64_t tiles = 0;
    };
    State state() const { return {m_gram, m_half_gram, m_frame_sum, m_rows, m_tiles}; }
    /// The accumulator that state() came from; throws modestack::Error (internal) when
    /// the sizes disagree.
    static GramAccumulator from_state(const State& state);

private:
    Eigen::MatrixXd m_gram;
    std::array<Eigen::MatrixXd, 2> m_half_gram;
    Eigen::VectorXd m_frame_sum;
    std::int64_t m_rows = 0;
    std::int64_t m_tiles = 0;
};

} // namespace modestack::lowrank
