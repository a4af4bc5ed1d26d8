#pragma once
// The exact median of one pixel's samples over time, the hot step of firefly
// cleaning (a median of F values for every row of the shot).

#include <cstddef>

namespace modestack::lowrank {

// Median of values[0..count) (the mean of the two middle values when count is
// even; 0 when count is 0): the same bits as sorting and picking, without
// reordering values. scratch_a and scratch_b hold count values each. The values
// must not be NaN.
double row_median(const double* values, std::size_t count, double* scratch_a, double* scratch_b);

} // namespace modestack::lowrank
