// Feathered weights: exact Euclidean distances, weight 1 inside the dilated
// selection, 0 beyond the feather, a bounded slope (no seam), and the same
// result for any thread count.
#include "core/common/error.h"
#include "core/refine/feather.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::refine;

namespace {

std::vector<std::uint8_t> random_selection(int width, int height, double density, unsigned seed)
{
    std::mt19937 generator(seed);
    std::bernoulli_distribution pick(density);
    std::vector<std::uint8_t> selection(static_cast<size_t>(width) * height);
    for (auto& flag : selection)
        flag = pick(generator) ? 1 : 0;
    return selection;
}

double brute_force_distance(const std::vector<std::uint8_t>& selection, int width, int height, int x, int y)
{
    double best = INFINITY;
    for (int v = 0; v < height; ++v)
        for (int u = 0; u < width; ++u)
            if (selection[static_cast<size_t>(v) * width + u])
                best = std::min(best, std::hypot(double(u - x), double(v - y)));
    return best;
}

} // namespace

TEST_CASE("weights follow the raised cosine of the exact Euclidean distance to the selection")
{
    const int width = 57, height = 23;
    FeatherOptions options;
    options.dilation = 2;
    options.feather = 4;
    auto selection = random_selection(width, height, 0.004, 3);
    std::vector<float> weights(selection.size());
    feathered_weights(selection.data(), width, height, options, weights.data());
    const double span = options.feather + 1.0, pi = 3.14159265358979323846;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double d = brute_force_distance(selection, width, height, x, y);
            double expected = d <= options.dilation ? 1.0
                              : d < options.dilation + span
                                  ? 0.5 * (1 + std::cos(pi * (d - options.dilation) / span))
                                  : 0.0;
            CAPTURE(x);
            CAPTURE(y);
            CHECK(weights[static_cast<size_t>(y) * width + x] == doctest::Approx(expected).epsilon(1e-6));
        }
}

TEST_CASE("the weight changes by at most pi / (2 (feather + 1)) between neighbours: no step at the border")
{
    const int width = 80, height = 60;
    auto selection = random_selection(width, height, 0.01, 11);
    for (int feather : {2, 4, 8}) {
        FeatherOptions options;
        options.dilation = 1;
        options.feather = feather;
        std::vector<float> weights(selection.size());
        feathered_weights(selection.data(), width, height, options, weights.data());
        double largest_step = 0;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x + 1 < width; ++x)
                largest_step = std::max(
                    largest_step, double(std::fabs(weights[y * width + x + 1] - weights[y * width + x])));
        // The raised cosine's steepest slope is pi / (2 span) per pixel of distance,
        // and neighbours differ by at most one pixel of distance.
        CHECK(largest_step <= 3.14159265358979323846 / (2 * (feather + 1)) + 1e-6);
        CHECK(largest_step > 0);
    }
}

TEST_CASE("feathered weights are the same for one and two threads, and bad distances are refused")
{
    const int width = 64, height = 48;
    auto selection = random_selection(width, height, 0.02, 5);
    FeatherOptions options;
    std::vector<float> one(selection.size()), two(selection.size());
    tbb::task_arena(1).execute(
        [&] { feathered_weights(selection.data(), width, height, options, one.data()); });
    tbb::task_arena(2).execute(
        [&] { feathered_weights(selection.data(), width, height, options, two.data()); });
    CHECK(one == two);
    std::vector<std::uint8_t> empty(selection.size(), 0);
    feathered_weights(empty.data(), width, height, options, one.data());
    CHECK(std::all_of(one.begin(), one.end(), [](float w) { return w == 0.0f; }));
    options.feather = -1;
    CHECK_THROWS_AS(feathered_weights(selection.data(), width, height, options, one.data()), Error);
}
