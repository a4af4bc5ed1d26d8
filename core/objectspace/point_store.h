// The points × frames matrix kept in memory for object space: the engine's
// rebuild (the surface filter works from it, frame by frame) and, when the
// memory budget holds it, the engine's noisy input (the residuals the noise
// level and sigma need after the rebuild, without reading the points files
// again). The engine's own sigma is kept only where no surface filter replaces
// it (points without positions and normals).
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstddef>
#include <vector>

namespace modestack::objectspace {

/// A FrameSource that keeps a copy of every row read from another: the engine
/// reads every row of every frame in pass 1, so afterwards the whole input is here.
class KeepingSource : public denoise::ForwardingSource {
public:
    explicit KeepingSource(denoise::FrameSource& inner);
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   denoise::PassThroughRows* pass_through) override;
    /// Frame `frame_index` as read, [row][x][channel].
    const float* frame(int frame_index) const { return m_rows[static_cast<std::size_t>(frame_index)].data(); }

private:
    std::size_t row_values() const { return static_cast<std::size_t>(m_shape.width) * m_shape.channels; }
    denoise::ShotShape m_shape;
    std::vector<std::vector<float>> m_rows; // per frame, [row][x][channel]
};

/// The engine's result for every point and frame, kept in memory.
class PointStore : public denoise::FrameSink {
public:
    /// `keep_sigma`: also keep the engine's sigma (else sigma(t) is null).
    PointStore(denoise::ShotShape shape, bool keep_sigma);
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const denoise::PassThroughRows* pass_through) override;
    /// Frame `frame_index`'s values and sigma, [point][channel] (padding points at the end).
    const float* values(int frame_index) const
    {
        return m_values[static_cast<std::size_t>(frame_index)].data();
    }
    const float* sigma(int frame_index) const
    {
        return m_sigma.empty() ? nullptr : m_sigma[static_cast<std::size_t>(frame_index)].data();
    }

private:
    denoise::ShotShape m_shape;
    std::vector<std::vector<float>> m_values, m_sigma;
};

} // namespace modestack::objectspace
