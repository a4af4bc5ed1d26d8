// Deterministic per-sample random numbers for the path tracer. Every number is a
// function of (seed, frame, pixel, sample index, dimension) alone, never drawn
// from a shared generator, so a frame is bit-identical for any thread count and
// tile order, and a pixel's samples are the same whether the whole frame or only
// that pixel is rendered. Numbers come in pairs of dimensions: each pair is the 2D
// Sobol (0,2)-sequence, Owen-scrambled with a hash (Burley 2020, "Practical
// Hash-based Owen Scrambling"), with the sample index itself Owen-scrambled per
// pixel and pair so that pairs are independent of each other. For a power-of-two
// spp the samples of one pixel in one pair form a (0,m,2)-net (stratified in
// every elementary interval); for other counts they stay well spread.
#pragma once

#include <cstdint>

namespace modestack::render {

/// A point in [0, 1)².
struct Sample2 {
    float u, v;
};

/// Mixes the bits of a 64-bit value (MurmurHash3's 64-bit finalizer).
std::uint64_t mix_bits(std::uint64_t value);

/// The sample stream of one pixel.
class PixelSampler {
public:
    /// Sampler of pixel (`x`, `y`) of frame `frame` with seed `seed`; with
    /// `fixed_seed` the frame is left out of the hash, so every frame gets the same
    /// numbers (temporally correlated noise).
    PixelSampler(std::uint64_t seed, int frame, bool fixed_seed, int x, int y);

    /// Dimensions 2·`pair` and 2·`pair`+1 of sample `sample_index`, each in [0, 1).
    Sample2 get_2d(std::uint32_t sample_index, std::uint32_t pair) const;

private:
    std::uint64_t m_pixel_key;
};

} // namespace modestack::render
