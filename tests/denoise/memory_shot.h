// Test doubles of the denoise engine's stream ends: a shot held in memory and a
// sink that collects what the engine writes, checking rows arrive in order.
#pragma once

#include "core/denoise/engine.h"
#include "core/denoise/frame_stream.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace modestack::denoise::testing {

// A shot held in memory: frames of width × height × channels floats.
struct MemoryShot : FrameSource {
    ShotShape size;
    std::vector<std::vector<float>> frames;
    /// Optional auxiliary layers, frames like `frames`: the variance of each sample
    /// (channels as the shot), and features with their own channel counts.
    std::vector<std::vector<float>> variance;
    /// Optional variance of each layer on its own (FrameSource::layer_variance_channels):
    /// per layer, its frames ([row][x][channel of the layer]; none: the layer has none).
    std::vector<std::vector<std::vector<float>>> layer_variance;
    struct Feature {
        int channels = 0;
        std::vector<std::vector<float>> frames;
    };
    Feature albedo, normal, depth;
    ShotShape shape() const override { return size; }
    void read_rows(int frame, int row_begin, int row_end, float* destination,
                   PassThroughRows* /*pass_through*/) override
    {
        std::size_t row = static_cast<std::size_t>(size.width) * size.channels;
        std::copy(frames[frame].begin() + row_begin * row, frames[frame].begin() + row_end * row, destination);
    }
    const Feature* feature(Auxiliary kind) const
    {
        switch (kind) {
        case Auxiliary::Albedo: return &albedo;
        case Auxiliary::Normal: return &normal;
        case Auxiliary::Depth: return &depth;
        default: return nullptr;
        }
    }
    int auxiliary_channels(Auxiliary kind) const override
    {
        if (kind == Auxiliary::Variance)
            return variance.empty() ? 0 : size.channels;
        return feature(kind)->channels;
    }
    void read_auxiliary_rows(Auxiliary kind, int frame, int row_begin, int row_end, float* destination) override
    {
        REQUIRE(auxiliary_channels(kind) > 0);
        const std::vector<float>& source = kind == Auxiliary::Variance ? variance[frame] : feature(kind)->frames[frame];
        std::size_t row = static_cast<std::size_t>(size.width) * auxiliary_channels(kind);
        std::copy(source.begin() + row_begin * row, source.begin() + row_end * row, destination);
    }
    int layer_variance_channels(int layer) const override
    {
        if (static_cast<std::size_t>(layer) >= layer_variance.size() || layer_variance[layer].empty())
            return 0;
        return static_cast<int>(layer_variance[layer].front().size() /
                                (static_cast<std::size_t>(size.width) * size.height));
    }
    void read_layer_variance_rows(int layer, int frame, int row_begin, int row_end,
                                  float* destination) override
    {
        REQUIRE(layer_variance_channels(layer) > 0);
        const std::vector<float>& source = layer_variance[layer][frame];
        std::size_t row = static_cast<std::size_t>(size.width) * layer_variance_channels(layer);
        std::copy(source.begin() + row_begin * row, source.begin() + row_end * row, destination);
    }
};

// Collects what the engine writes, checking rows arrive in order.
struct MemorySink : FrameSink {
    ShotShape size;
    std::vector<std::vector<float>> rebuilt, sigma;
    std::vector<int> next_row;
    std::vector<bool> written;  ///< frames writes_frame() says yes to (empty: all)
    explicit MemorySink(const ShotShape& shape)
        : size(shape),
          rebuilt(shape.frames, std::vector<float>(std::size_t(shape.width) * shape.height * shape.channels)),
          sigma(rebuilt),
          next_row(shape.frames, 0)
    {
    }
    bool writes_frame(int frame) const override { return written.empty() || written[std::size_t(frame)]; }
    void write_rows(int frame, int row_begin, int row_end, const float* values, const float* errors,
                    const PassThroughRows* /*pass_through*/) override
    {
        CHECK(writes_frame(frame));
        CHECK(row_begin == next_row[frame]);
        next_row[frame] = row_end;
        std::size_t row = static_cast<std::size_t>(size.width) * size.channels;
        std::copy(values, values + (row_end - row_begin) * row, rebuilt[frame].begin() + row_begin * row);
        std::copy(errors, errors + (row_end - row_begin) * row, sigma[frame].begin() + row_begin * row);
    }
};

/// Mean squared difference of two shots of the same size (frames of samples).
inline double mean_square(const std::vector<std::vector<float>>& a, const std::vector<std::vector<float>>& b)
{
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t t = 0; t < a.size(); ++t)
        for (std::size_t i = 0; i < a[t].size(); ++i, ++count)
            sum += (double(a[t][i]) - b[t][i]) * (double(a[t][i]) - b[t][i]);
    return sum / count;
}

/// The engine's defaults with the mode filter on and no firefly clamp: for
/// shots under Gaussian noise, which has no fireflies.
inline Settings gaussian_noise_settings()
{
    Settings settings;
    settings.mode_filter.enabled = true;
    settings.outliers.fireflies = false;
    return settings;
}

}  // namespace modestack::denoise::testing
