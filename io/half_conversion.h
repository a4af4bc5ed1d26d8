#pragma once
// half <-> float conversion of whole rows: the first step after every read value
// of a half-float input is decompressed, and the last before every written one
// is compressed.

#include <cstddef>
#include <cstdint>

namespace modestack::io {

// halves[i] = the bits of Imath::half(values[i]) for i < count (round to nearest
// even, overflow to infinity, NaN stays NaN). Uses the CPU's F16C instructions
// when it has them (8 values per instruction) and Imath otherwise; both give
// the same bits.
void floats_to_halves(const float* values, std::uint16_t* halves, std::size_t count);

// values[i] = float(Imath::half with bits halves[i]) for i < count: exact (every
// half is a float), F16C when the CPU has it, Imath's table otherwise, same bits.
void halves_to_floats(const std::uint16_t* halves, float* values, std::size_t count);

} // namespace modestack::io
