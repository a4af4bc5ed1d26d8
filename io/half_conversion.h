#pragma once
// float -> half conversion of whole rows: the last step before every written
// value of a half-float output is compressed.

#include <cstddef>
#include <cstdint>

namespace modestack::io {

// halves[i] = the bits of Imath::half(values[i]) for i < count (round to nearest
// even, overflow to infinity, NaN stays NaN). Uses the CPU's F16C instructions
// when it has them (8 values per instruction) and Imath otherwise; both give
// the same bits.
void floats_to_halves(const float* values, std::uint16_t* halves, std::size_t count);

} // namespace modestack::io
