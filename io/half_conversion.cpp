#include "io/half_conversion.h"

#include <Imath/half.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <cpuid.h>
#include <immintrin.h>
#define MODESTACK_HAVE_F16C_PATH 1
#endif

namespace modestack::io {
namespace {

void imath_floats_to_halves(const float* values, std::uint16_t* halves, std::size_t count)
{
    for (std::size_t i = 0; i < count; ++i)
        halves[i] = Imath::half(values[i]).bits();
}

void imath_halves_to_floats(const std::uint16_t* halves, float* values, std::size_t count)
{
    for (std::size_t i = 0; i < count; ++i) {
        Imath::half value;
        value.setBits(halves[i]);
        values[i] = static_cast<float>(value);
    }
}

#ifdef MODESTACK_HAVE_F16C_PATH
// Compiled for AVX+F16C whatever the build's target, called only on CPUs that
// have both. F16C rounds like Imath (to nearest even) and agrees with it on
// every non-NaN float (checked over all 2^32 bit patterns); NaN payloads
// differ, so blocks holding a NaN go through Imath.
__attribute__((target("avx,f16c"))) void f16c_floats_to_halves(const float* values, std::uint16_t* halves,
                                                               std::size_t count)
{
    std::size_t i = 0;
    for (; i + 8 <= count; i += 8) {
        const __m256 block = _mm256_loadu_ps(values + i);
        if (_mm256_movemask_ps(_mm256_cmp_ps(block, block, _CMP_UNORD_Q)) != 0) {
            imath_floats_to_halves(values + i, halves + i, 8);
            continue;
        }
        const __m128i converted = _mm256_cvtps_ph(block, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(halves + i), converted);
    }
    imath_floats_to_halves(values + i, halves + i, count - i);
}

// F16C makes a signalling NaN quiet, Imath keeps its bits: blocks holding a NaN
// (or an infinity: same exponent) go through Imath.
__attribute__((target("avx,f16c"))) void f16c_halves_to_floats(const std::uint16_t* halves, float* values,
                                                               std::size_t count)
{
    std::size_t i = 0;
    const __m128i exponent = _mm_set1_epi16(0x7C00);
    for (; i + 8 <= count; i += 8) {
        const __m128i block = _mm_loadu_si128(reinterpret_cast<const __m128i*>(halves + i));
        const __m128i top_exponent = _mm_cmpeq_epi16(_mm_and_si128(block, exponent), exponent);
        if (_mm_movemask_epi8(top_exponent) != 0) {
            imath_halves_to_floats(halves + i, values + i, 8);
            continue;
        }
        _mm256_storeu_ps(values + i, _mm256_cvtph_ps(block));
    }
    imath_halves_to_floats(halves + i, values + i, count - i);
}

// From CPUID, not __builtin_cpu_supports: clang 14's does not know "f16c".
bool use_f16c()
{
    static const bool available = [] {
        unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
        if (!__get_cpuid(1, &eax, &ebx, &ecx, &edx))
            return false;
        constexpr unsigned kOsSavesState = 1u << 27, kAvx = 1u << 28, kF16c = 1u << 29;
        if ((ecx & (kOsSavesState | kAvx | kF16c)) != (kOsSavesState | kAvx | kF16c))
            return false;
        unsigned low = 0, high = 0;  // XCR0: the OS saves the SSE and AVX registers
        __asm__("xgetbv" : "=a"(low), "=d"(high) : "c"(0));
        return (low & 6u) == 6u;
    }();
    return available;
}
#endif

} // namespace

void floats_to_halves(const float* values, std::uint16_t* halves, std::size_t count)
{
#ifdef MODESTACK_HAVE_F16C_PATH
    if (use_f16c()) {
        f16c_floats_to_halves(values, halves, count);
        return;
    }
#endif
    imath_floats_to_halves(values, halves, count);
}

void halves_to_floats(const std::uint16_t* halves, float* values, std::size_t count)
{
#ifdef MODESTACK_HAVE_F16C_PATH
    if (use_f16c()) {
        f16c_halves_to_floats(halves, values, count);
        return;
    }
#endif
    imath_halves_to_floats(halves, values, count);
}

} // namespace modestack::io
