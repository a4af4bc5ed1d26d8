// Crop windows of a mask (core/refine/crop_windows.h): clusters are 8-connected,
// two far clusters stay apart, two near ones merge exactly when the merge saves
// pixels against the overhead, merges cascade, every pixel stays covered and no
// pair is left that would save by merging; and the renderers' normalised forms
// give back exactly the window under each renderer's own rounding rule (the
// y flip of Cycles and Karma included).
#include "core/refine/crop_windows.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

using namespace modestack::refine;

namespace {

struct Mask {
    int width, height;
    std::vector<std::uint8_t> pixels;
    Mask(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h, 0) {}
    void fill(int x0, int y0, int x1, int y1)
    {
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                pixels[static_cast<size_t>(y) * width + x] = 1;
    }
    std::vector<PixelWindow> windows(std::int64_t overhead) const
    {
        return crop_windows(pixels.data(), width, height, overhead);
    }
};

} // namespace

TEST_CASE("cluster windows are the bounding boxes of 8-connected clusters")
{
    Mask mask(10, 8);
    mask.fill(1, 1, 3, 3);
    mask.fill(3, 3, 4, 4); // touches the first cluster at a corner only: the same cluster
    mask.fill(7, 0, 9, 2);
    auto windows = cluster_windows(mask.pixels.data(), mask.width, mask.height);
    REQUIRE(windows.size() == 2);
    CHECK(windows[0] == PixelWindow{7, 0, 9, 2}); // its first pixel comes first in row-major order
    CHECK(windows[1] == PixelWindow{1, 1, 4, 4});
    CHECK(cluster_windows(Mask(5, 5).pixels.data(), 5, 5).empty());
}

TEST_CASE("two far clusters stay apart and two near ones merge")
{
    Mask far(100, 100);
    far.fill(2, 2, 6, 6);
    far.fill(90, 90, 94, 94);
    auto apart = far.windows(4096); // the union (92 x 92 = 8464) costs more than 16 + 16 + 4096
    REQUIRE(apart.size() == 2);
    CHECK(windows_cost(apart, 4096) == 16 + 16 + 2 * 4096);

    Mask near(100, 100);
    near.fill(10, 10, 14, 14);
    near.fill(16, 10, 20, 14); // a gap of 2 columns: the union is 10 x 4 = 40 pixels
    auto merged = near.windows(64);
    REQUIRE(merged.size() == 1);
    CHECK(merged[0] == PixelWindow{10, 10, 20, 14});
}

TEST_CASE(
    "the merge rule: merge exactly when the union costs fewer pixels than the two windows and one overhead")
{
    const PixelWindow a{10, 10, 14, 14}, b{16, 10, 20, 14}; // 16 + 16 pixels, union 40
    CHECK(merge_saving(a, b, 0) == -8);
    CHECK(merge_saving(a, b, 8) == 0);
    CHECK(merge_saving(a, b, 9) == 1);
    CHECK(merge_windows({a, b}, 0).size() == 2);
    CHECK(merge_windows({a, b}, 8).size() == 2); // no saving: not merged
    CHECK(merge_windows({a, b}, 9).size() == 1);
    // Overlapping windows merge even without overhead when the union is no larger than their sum.
    CHECK(merge_windows({{0, 0, 4, 4}, {2, 0, 6, 4}}, 0).size() == 1);
}

TEST_CASE("merges cascade: a grown window can pay for a merge that did not pay before")
{
    // a and b merge (saving 1); the union then reaches c closely enough to merge, which c alone and a did
    // not.
    const PixelWindow a{0, 0, 4, 4}, b{6, 0, 10, 4}, c{0, 4, 10, 8};
    const std::int64_t overhead = 9;
    CHECK(merge_saving(a, c, overhead) <= 0);
    CHECK(merge_saving(enclosing_window(a, b), c, overhead) > 0);
    auto windows = merge_windows({a, c, b}, overhead);
    REQUIRE(windows.size() == 1);
    CHECK(windows[0] == PixelWindow{0, 0, 10, 8});
}

TEST_CASE("merged windows cover every mask pixel and leave no pair that would save by merging")
{
    std::mt19937 random(7);
    for (int trial = 0; trial < 20; ++trial) {
        Mask mask(80, 60);
        std::uniform_int_distribution<int> x(0, 75), y(0, 55), size(1, 4);
        for (int blob = 0; blob < 12; ++blob) {
            int x0 = x(random), y0 = y(random);
            mask.fill(x0, y0, x0 + size(random), y0 + size(random));
        }
        const std::int64_t overhead = trial * 10;
        auto clusters = cluster_windows(mask.pixels.data(), mask.width, mask.height);
        auto windows = mask.windows(overhead);
        CHECK(windows_cost(windows, overhead) <= windows_cost(clusters, overhead));
        for (size_t i = 0; i < windows.size(); ++i)
            for (size_t j = i + 1; j < windows.size(); ++j)
                CHECK(merge_saving(windows[i], windows[j], overhead) <= 0);
        for (int py = 0; py < mask.height; ++py)
            for (int px = 0; px < mask.width; ++px) {
                if (!mask.pixels[static_cast<size_t>(py) * mask.width + px])
                    continue;
                bool covered = false;
                for (const auto& w : windows)
                    covered = covered || (px >= w.x0 && px < w.x1 && py >= w.y0 && py < w.y1);
                CHECK(covered);
            }
    }
}

TEST_CASE("the normalised forms give back the window under each renderer's rounding, y flipped where y is up")
{
    // A window at the top of a 100-row image is at the top of Cycles' and USD's y-up range.
    const NormalisedWindow top = cycles_border({0, 0, 10, 10}, 100, 100);
    CHECK(top.max_y == 1.0);
    CHECK(top.min_y == doctest::Approx(0.9).epsilon(0.01));
    const NormalisedWindow ndc = ndc_data_window({0, 0, 10, 10}, 100, 100);
    CHECK(ndc.min_y == doctest::Approx(0.9));
    CHECK(ndc.max_y == 1.0);
    CHECK(renderman_crop_window({0, 0, 10, 10}, 100, 100).min_y == 0.0); // RenderMan's y is down

    for (int width : {7, 1920})
        for (int height : {5, 1080}) {
            const int step_x = width > 100 ? 37 : 1, step_y = height > 100 ? 29 : 1;
            for (int x0 = 0; x0 < width; x0 += step_x)
                for (int x1 = x0 + 1; x1 <= width; x1 += step_x)
                    for (int y0 = 0; y0 < height; y0 += step_y)
                        for (int y1 = y0 + 1; y1 <= height; y1 += step_y) {
                            const PixelWindow window{x0, y0, x1, y1};
                            // Blender: rows from the bottom, int(border · size), the border held in float.
                            const NormalisedWindow border = cycles_border(window, width, height);
                            auto blender = [](double v, int size) {
                                return static_cast<int>(static_cast<float>(v) * static_cast<float>(size));
                            };
                            CHECK(blender(border.min_x, width) == x0);
                            CHECK(blender(border.max_x, width) == x1);
                            CHECK(blender(border.min_y, height) == height - y1);
                            CHECK(blender(border.max_y, height) == height - y0);
                            // RenderMan: ceil(res · min) <= pixel <= ceil(res · max - 1), rows from the top.
                            const NormalisedWindow crop = renderman_crop_window(window, width, height);
                            CHECK(static_cast<int>(std::ceil(width * crop.min_x)) == x0);
                            CHECK(static_cast<int>(std::ceil(width * crop.max_x - 1)) == x1 - 1);
                            CHECK(static_cast<int>(std::ceil(height * crop.min_y)) == y0);
                            CHECK(static_cast<int>(std::ceil(height * crop.max_y - 1)) == y1 - 1);
                            // USD/Karma: the pixels whose centres lie inside, rows from the bottom.
                            const NormalisedWindow data = ndc_data_window(window, width, height);
                            CHECK(std::ceil(width * data.min_x - 0.5) == x0);
                            CHECK(std::floor(width * data.max_x - 0.5) == x1 - 1);
                            CHECK(std::ceil(height * data.min_y - 0.5) == height - y1);
                            CHECK(std::floor(height * data.max_y - 0.5) == height - y0 - 1);
                        }
        }
}
