// Owen-scrambled Sobol pairs from hashes (see sampler.h).
#include "core/render/sampler.h"

namespace modestack::render {
namespace {

std::uint32_t reverse_bits(std::uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

// A hash in which each output bit depends only on the input bits at or below it
// (Laine–Karras style, with Vegdahl's constants): applied to bit-reversed values
// it flips each digit depending on the more significant digits only, which is
// exactly a nested uniform (Owen) scramble.
std::uint32_t laine_karras_permutation(std::uint32_t x, std::uint32_t seed)
{
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Second dimension of the Sobol sequence (its generator matrix is Pascal's
// triangle mod 2); the first is the van der Corput sequence, reverse_bits(index).
std::uint32_t sobol_second_dimension_bitwise(std::uint32_t index)
{
    std::uint32_t result = 0;
    for (std::uint32_t column = 1u << 31; index != 0; index >>= 1, column ^= column >> 1)
        if (index & 1u)
            result ^= column;
    return result;
}

// The map is linear over GF(2), so it is the XOR of its values on the four bytes
// of the index: four 256-entry tables instead of a 32-step loop (scrambled indices
// use all 32 bits, and this was a third of the render time).
struct SobolByteTables {
    std::uint32_t values[4][256];
};

const SobolByteTables& sobol_byte_tables()
{
    static const SobolByteTables tables = [] {
        SobolByteTables built{};
        for (int byte = 0; byte < 4; ++byte)
            for (std::uint32_t value = 0; value < 256; ++value)
                built.values[byte][value] = reverse_bits(sobol_second_dimension_bitwise(value << (8 * byte)));
        return built;
    }();
    return tables;
}

// The second Sobol dimension with its bits reversed, which is the form the
// scramble below works on.
std::uint32_t reversed_sobol_second_dimension(std::uint32_t index)
{
    const SobolByteTables& tables = sobol_byte_tables();
    return tables.values[0][index & 0xffu] ^ tables.values[1][(index >> 8) & 0xffu] ^
           tables.values[2][(index >> 16) & 0xffu] ^ tables.values[3][index >> 24];
}

// The top 24 bits as a float in [0, 1): exact, and never rounds up to 1.
float to_unit_float(std::uint32_t bits)
{
    return static_cast<float>(bits >> 8) * (1.0f / 16777216.0f);
}

} // namespace

std::uint64_t mix_bits(std::uint64_t value)
{
    value ^= value >> 33;
    value *= 0xff51afd7ed558ccdull;
    value ^= value >> 33;
    value *= 0xc4ceb9fe1a85ec53ull;
    value ^= value >> 33;
    return value;
}

PixelSampler::PixelSampler(std::uint64_t seed, int frame, bool fixed_seed, int x, int y)
{
    std::uint64_t key = mix_bits(seed ^ 0x9e3779b97f4a7c15ull);
    if (!fixed_seed)
        key = mix_bits(key ^ static_cast<std::uint32_t>(frame));
    key = mix_bits(key ^ (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32 |
                          static_cast<std::uint32_t>(y)));
    m_pixel_key = key;
}

Sample2 PixelSampler::get_2d(std::uint32_t sample_index, std::uint32_t pair) const
{
    std::uint64_t pair_key = mix_bits(m_pixel_key ^ (0xd1b54a32d192ed03ull * (pair + 1)));
    std::uint64_t scramble_key = mix_bits(pair_key);
    // An Owen scramble is reverse_bits ∘ laine_karras_permutation ∘ reverse_bits;
    // the reversals that cancel out are left away. First the sample index itself
    // is scrambled (a different order of the sequence per pixel and pair), then
    // each coordinate: dimension 0 is reverse_bits(index), dimension 1 the Sobol one.
    std::uint32_t reversed_index =
        laine_karras_permutation(reverse_bits(sample_index), static_cast<std::uint32_t>(pair_key));
    std::uint32_t index = reverse_bits(reversed_index);
    std::uint32_t u = reverse_bits(laine_karras_permutation(index, static_cast<std::uint32_t>(scramble_key)));
    std::uint32_t v = reverse_bits(laine_karras_permutation(reversed_sobol_second_dimension(index),
                                                            static_cast<std::uint32_t>(scramble_key >> 32)));
    return {to_unit_float(u), to_unit_float(v)};
}

} // namespace modestack::render
