// row_median: the same value as sorting and picking the middle (mean of the two
// middle values for even counts) on every count from 1 to 300 and on the orders
// and ties that trouble quickselects, and it leaves its input alone.
#include "core/lowrank/row_median.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

using modestack::lowrank::row_median;

namespace {

double sorted_median(std::vector<double> values)
{
    std::sort(values.begin(), values.end());
    const std::size_t middle = values.size() / 2;
    return values.size() % 2 ? values[middle] : 0.5 * (values[middle - 1] + values[middle]);
}

void check_median(const std::vector<double>& values)
{
    std::vector<double> input = values, scratch_a(values.size()), scratch_b(values.size());
    const double median = row_median(input.data(), input.size(), scratch_a.data(), scratch_b.data());
    REQUIRE(median == sorted_median(values));
    REQUIRE(input == values);
}

// The orders and value sets a pivot rule can trip on, `count` values long.
std::vector<std::vector<double>> tricky_rows(std::size_t count, std::mt19937_64& random)
{
    std::vector<std::vector<double>> rows(8, std::vector<double>(count));
    std::normal_distribution<double> normal(0.0, 1.0);
    std::uniform_int_distribution<int> few(0, 3);
    for (std::size_t i = 0; i < count; ++i) {
        const double x = static_cast<double>(i);
        rows[0][i] = std::exp(normal(random));                         // skewed noise
        rows[1][i] = few(random);                                      // four values, many ties
        rows[2][i] = 1.5;                                              // all equal
        rows[3][i] = x;                                                // ascending
        rows[4][i] = -x;                                               // descending, negative
        rows[5][i] = std::min(x, static_cast<double>(count) - x);     // organ pipe
        rows[6][i] = i % 2 ? x : -x;                                   // alternating
        rows[7][i] = i + 1 == count ? 1e30 : normal(random) * 1e-3;    // one firefly
    }
    return rows;
}

} // namespace

TEST_CASE("row_median equals the sorted middle on every count from 1 to 300")
{
    std::mt19937_64 random(7);
    for (std::size_t count = 1; count <= 300; ++count)
        for (const std::vector<double>& row : tricky_rows(count, random)) {
            CAPTURE(count);
            check_median(row);
        }
}

TEST_CASE("row_median equals the sorted middle on many random rows of 24, 100 and 101 frames")
{
    std::mt19937_64 random(11);
    std::gamma_distribution<double> radiance(2.0, 0.5);
    for (std::size_t count : {24, 100, 101})
        for (int trial = 0; trial < 3000; ++trial) {
            std::vector<double> row(count);
            for (double& value : row)  // rounded to float like the samples it is used on
                value = static_cast<float>(radiance(random));
            check_median(row);
        }
}

TEST_CASE("row_median of nothing is 0")
{
    CHECK(row_median(nullptr, 0, nullptr, nullptr) == 0.0);
}
