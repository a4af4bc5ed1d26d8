// floats_to_halves gives Imath::half's bits: on a sweep over the float bit
// patterns (normals, denormals, overflow, infinities), at the rounding ties, at
// every length around the 8-value blocks, and NaN stays NaN; halves_to_floats
// gives Imath's floats for all 65536 halves.
#include "io/half_conversion.h"

#include <Imath/half.h>
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

using modestack::io::floats_to_halves;

namespace {

float float_of_bits(std::uint32_t bits)
{
    float value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}

} // namespace

TEST_CASE("floats_to_halves matches Imath on a sweep of float bit patterns")
{
    std::vector<float> values;
    for (std::uint64_t bits = 0; bits < (std::uint64_t{1} << 32); bits += 4093) {
        const float value = float_of_bits(static_cast<std::uint32_t>(bits));
        if (!std::isnan(value))
            values.push_back(value);
    }
    // Ties between two halves (round to even), the denormal and overflow edges.
    for (float value : {1.0f + 1.0f / 2048, 1.0f + 3.0f / 2048, 65504.0f, 65519.99f, 65520.0f, 6.1035156e-05f,
                        5.9604645e-08f, 2.9802322e-08f, 2.9802326e-08f, -0.0f,
                        std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()})
        values.push_back(value);
    std::vector<std::uint16_t> halves(values.size());
    floats_to_halves(values.data(), halves.data(), values.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < values.size(); ++i)
        mismatches += halves[i] != Imath::half(values[i]).bits() ? 1 : 0;
    CHECK(values.size() > 1000000);
    CHECK(mismatches == 0);
}

TEST_CASE("floats_to_halves converts every length and keeps NaN a NaN")
{
    for (std::size_t count = 0; count <= 33; ++count) {
        std::vector<float> values(count);
        for (std::size_t i = 0; i < count; ++i)
            values[i] = i == 5 ? std::numeric_limits<float>::quiet_NaN() : 0.1f * static_cast<float>(i) - 1.3f;
        std::vector<std::uint16_t> halves(count + 1, 0xBEEF);
        floats_to_halves(values.data(), halves.data(), count);
        CAPTURE(count);
        for (std::size_t i = 0; i < count; ++i) {
            Imath::half converted;
            converted.setBits(halves[i]);
            if (i == 5)
                CHECK(converted.isNan());
            else
                CHECK(halves[i] == Imath::half(values[i]).bits());
        }
        CHECK(halves[count] == 0xBEEF);  // nothing written past the end
    }
}

TEST_CASE("halves_to_floats matches Imath on every half, NaN payloads included, at every length")
{
    std::vector<std::uint16_t> halves(65536 + 5);
    for (std::size_t i = 0; i < halves.size(); ++i)
        halves[i] = static_cast<std::uint16_t>(i);
    std::vector<float> values(halves.size() + 1, -7.0f);
    modestack::io::halves_to_floats(halves.data(), values.data(), halves.size());
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < halves.size(); ++i) {
        Imath::half half;
        half.setBits(halves[i]);
        const float expected = static_cast<float>(half);
        mismatches += std::memcmp(&expected, &values[i], sizeof expected) != 0 ? 1 : 0;
    }
    CHECK(mismatches == 0);
    CHECK(values[halves.size()] == -7.0f);  // nothing written past the end
}
