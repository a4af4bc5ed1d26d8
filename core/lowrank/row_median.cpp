#include "core/lowrank/row_median.h"

#include <algorithm>
#include <limits>
#include <utility>

namespace modestack::lowrank {
namespace {

// The k-th smallest of values[0..count). A quickselect whose partition has no
// data-dependent branch: every value is stored at both the next low and the next
// high slot and only the matching counter moves (std::nth_element's branchy
// partition mispredicts on about every other sample of noisy data, which made
// it 2-3x slower on rows of 24-400 frames). Values equal to the pivot are
// counted, not kept, so each round drops at least the pivot.
double select_kth(const double* values, std::size_t count, std::size_t k, double* from, double* to)
{
    constexpr std::size_t kSmall = 8;
    const double* in = values;
    std::size_t rounds_left = 64;  // median-of-3 pivots never need this many on real rows
    while (count > kSmall) {
        if (rounds_left-- == 0) {  // a pathological order: finish with the library's introselect
            std::copy(in, in + count, to);
            std::nth_element(to, to + k, to + count);
            return to[k];
        }
        const double first = in[0], middle = in[count / 2], last = in[count - 1];
        const double pivot = std::max(std::min(first, middle), std::min(std::max(first, middle), last));
        std::size_t low = 0, high = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const double value = in[i];
            to[low] = value;
            to[count - 1 - high] = value;
            low += value < pivot ? 1 : 0;
            high += value > pivot ? 1 : 0;
        }
        if (k < low) {
            count = low;
        } else if (k < count - high) {
            return pivot;
        } else {
            k -= count - high;
            std::copy(to + (count - high), to + count, to);
            count = high;
        }
        in = to;
        std::swap(from, to);
    }
    double small[kSmall];
    std::copy(in, in + count, small);
    std::sort(small, small + count);
    return small[k];
}

} // namespace

double row_median(const double* values, std::size_t count, double* scratch_a, double* scratch_b)
{
    if (count == 0)
        return 0.0;
    const std::size_t middle = count / 2;
    const double upper = select_kth(values, count, middle, scratch_a, scratch_b);
    if (count % 2 == 1)
        return upper;
    // The value just below the middle: the largest value under `upper`, or
    // `upper` itself when fewer than `middle` values lie under it (ties).
    std::size_t below = 0;
    double lower = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < count; ++i) {
        const bool under = values[i] < upper;
        below += under ? 1 : 0;
        lower = std::max(lower, under ? values[i] : -std::numeric_limits<double>::infinity());
    }
    if (below < middle)
        lower = upper;
    return 0.5 * (lower + upper);
}

} // namespace modestack::lowrank
