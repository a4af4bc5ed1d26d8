// The shape in which the data matrix X reaches the low-rank code. X has one row
// per sample (pixel × channel) and one column per frame; the io layer hands it
// over in horizontal bands of scanlines, stored frame-major so that each frame's
// part of a band is one contiguous image band. Pass-based algorithms (randomized
// SVD) see the whole matrix as a BandPass: a callable that runs one pass over all
// bands, always in the same order, so that results are reproducible.
#pragma once

#include <cstdint>
#include <functional>

namespace modestack::lowrank {

/// A band of X: `rows` samples of each of `frames` frames. Frame f's values are
/// data[f * frame_stride + i], i < rows (frame-major; one image band per frame).
/// For images, rows = width * band_height * channels, samples interleaved as [y][x][c].
struct BandView {
    const float* data = nullptr;
    std::int64_t rows = 0;
    int frames = 0;
    std::int64_t frame_stride = 0;

    /// Value of sample `row` in frame `frame`.
    float at(std::int64_t row, int frame) const { return data[frame * frame_stride + row]; }
};

/// The writable twin of BandView (same layout).
struct MutableBandView {
    float* data = nullptr;
    std::int64_t rows = 0;
    int frames = 0;
    std::int64_t frame_stride = 0;

    /// Reference to sample `row` of frame `frame`.
    float& at(std::int64_t row, int frame) const { return data[frame * frame_stride + row]; }
    /// The same band, read-only.
    BandView view() const { return BandView{data, rows, frames, frame_stride}; }
};

/// One pass over every band of X, in a fixed order: calls `visit` once per band.
using BandPass = std::function<void(const std::function<void(const BandView&)>& visit)>;

} // namespace modestack::lowrank
