// Synthetic data for the low-rank tests: frame-major matrices X = spatial ×
// temporalᵀ (+ noise) built from a fixed seed, and helpers to view them as bands.
#pragma once

#include "core/lowrank/band.h"
#include "core/lowrank/randomized_svd.h"

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <vector>

namespace modestack::lowrank::testing {

/// A whole frame-major matrix held in memory (frame f's column is data[f*rows ..]).
struct FrameMatrix {
    std::vector<float> data;
    std::int64_t rows = 0;
    int frames = 0;

    FrameMatrix(std::int64_t row_count, int frame_count)
        : data(static_cast<std::size_t>(row_count * frame_count), 0.0f), rows(row_count), frames(frame_count)
    {
    }
    float& at(std::int64_t row, int frame) { return data[static_cast<std::size_t>(frame * rows + row)]; }
    float at(std::int64_t row, int frame) const { return data[static_cast<std::size_t>(frame * rows + row)]; }
    BandView view() const { return BandView{data.data(), rows, frames, rows}; }
    MutableBandView mutable_view() { return MutableBandView{data.data(), rows, frames, rows}; }
    /// Rows [row0, row0 + count) as a band.
    BandView band(std::int64_t row0, std::int64_t count) const
    {
        return BandView{data.data() + row0, count, frames, rows};
    }
};

/// Smooth temporal factors (F × rank): mode j is a slow cosine of frequency j with a
/// phase, mode 0 close to constant, each scaled by `amplitudes[j]`.
inline Eigen::MatrixXd smooth_temporal(int frames, const std::vector<double>& amplitudes)
{
    const int kept_modes = static_cast<int>(amplitudes.size());
    Eigen::MatrixXd temporal(frames, kept_modes);
    for (int j = 0; j < kept_modes; ++j)
        for (int t = 0; t < frames; ++t) {
            const double phase = 6.283185307179586 * (j * t / double(frames) + 0.17 * j);
            temporal(t, j) =
                amplitudes[static_cast<std::size_t>(j)] *
                (j == 0 ? 1.0 + 0.3 * std::sin(phase + 0.4 * t / double(frames)) : std::cos(phase));
        }
    return temporal;
}

/// X = U Wᵀ with U Gaussian (rows × rank) from `seed` and W = smooth_temporal.
inline FrameMatrix low_rank_matrix(std::int64_t rows, int frames, const std::vector<double>& amplitudes,
                                   std::uint64_t seed)
{
    const int kept_modes = static_cast<int>(amplitudes.size());
    const Eigen::MatrixXd spatial = gaussian_matrix(static_cast<int>(rows), kept_modes, seed);
    const Eigen::MatrixXd temporal = smooth_temporal(frames, amplitudes);
    FrameMatrix matrix(rows, frames);
    for (int t = 0; t < frames; ++t)
        for (std::int64_t i = 0; i < rows; ++i)
            matrix.at(i, t) = static_cast<float>(spatial.row(i).dot(temporal.row(t)));
    return matrix;
}

/// Adds i.i.d. Gaussian noise of standard deviation `sigma` to every sample.
inline void add_gaussian_noise(FrameMatrix& matrix, double sigma, std::uint64_t seed)
{
    const Eigen::MatrixXd noise = gaussian_matrix(static_cast<int>(matrix.rows), matrix.frames, seed);
    for (int t = 0; t < matrix.frames; ++t)
        for (std::int64_t i = 0; i < matrix.rows; ++i)
            matrix.at(i, t) += static_cast<float>(sigma * noise(i, t));
}

/// A BandPass over `matrix` in bands of `band_rows` rows.
inline BandPass pass_over(const FrameMatrix& matrix, std::int64_t band_rows)
{
    return [&matrix, band_rows](const std::function<void(const BandView&)>& visit) {
        for (std::int64_t row0 = 0; row0 < matrix.rows; row0 += band_rows)
            visit(matrix.band(row0, std::min(band_rows, matrix.rows - row0)));
    };
}

/// Σ (a − b)² over all samples, in double.
inline double squared_distance(const FrameMatrix& a, const FrameMatrix& b)
{
    double sum = 0;
    for (std::size_t k = 0; k < a.data.size(); ++k) {
        const double difference = double(a.data[k]) - double(b.data[k]);
        sum += difference * difference;
    }
    return sum;
}

/// Σ a² over all samples, in double.
inline double squared_norm(const FrameMatrix& a)
{
    double sum = 0;
    for (float value : a.data)
        sum += double(value) * double(value);
    return sum;
}

} // namespace modestack::lowrank::testing
