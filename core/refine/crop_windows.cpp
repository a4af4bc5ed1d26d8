#include "core/refine/crop_windows.h"

#include <algorithm>
#include <cstddef>

namespace modestack::refine {

PixelWindow enclosing_window(const PixelWindow& a, const PixelWindow& b)
{
    return {std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

std::int64_t merge_saving(const PixelWindow& a, const PixelWindow& b, std::int64_t overhead_pixels)
{
    return a.area() + b.area() + overhead_pixels - enclosing_window(a, b).area();
}

std::int64_t windows_cost(const std::vector<PixelWindow>& windows, std::int64_t overhead_pixels)
{
    std::int64_t cost = 0;
    for (const PixelWindow& window : windows)
        cost += window.area() + overhead_pixels;
    return cost;
}

std::vector<PixelWindow> cluster_windows(const std::uint8_t* mask, int width, int height)
{
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    std::vector<std::uint8_t> visited(pixels, 0);
    std::vector<std::size_t> stack;
    std::vector<PixelWindow> windows;
    for (std::size_t start = 0; start < pixels; ++start) {
        if (!mask[start] || visited[start])
            continue;
        const int start_x = static_cast<int>(start % width), start_y = static_cast<int>(start / width);
        PixelWindow box{start_x, start_y, start_x + 1, start_y + 1};
        visited[start] = 1;
        stack.push_back(start);
        while (!stack.empty()) {
            const std::size_t p = stack.back();
            stack.pop_back();
            const int x = static_cast<int>(p % width), y = static_cast<int>(p / width);
            box = enclosing_window(box, {x, y, x + 1, y + 1});
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int u = x + dx, v = y + dy;
                    if (u < 0 || u >= width || v < 0 || v >= height)
                        continue;
                    const std::size_t q = static_cast<std::size_t>(v) * width + u;
                    if (mask[q] && !visited[q]) {
                        visited[q] = 1;
                        stack.push_back(q);
                    }
                }
        }
        windows.push_back(box);
    }
    return windows;
}

std::vector<PixelWindow> merge_windows(std::vector<PixelWindow> windows, std::int64_t overhead_pixels)
{
    bool merged = true;
    while (merged) {
        merged = false;
        for (std::size_t i = 0; i < windows.size(); ++i)
            for (std::size_t j = i + 1; j < windows.size();) {
                if (merge_saving(windows[i], windows[j], overhead_pixels) > 0) {
                    windows[i] = enclosing_window(windows[i], windows[j]);
                    windows.erase(windows.begin() + static_cast<std::ptrdiff_t>(j));
                    merged = true;
                    j = i + 1; // window i grew: earlier partners may pay now
                } else {
                    ++j;
                }
            }
    }
    return windows;
}

std::vector<PixelWindow> crop_windows(const std::uint8_t* mask, int width, int height,
                                      std::int64_t overhead_pixels)
{
    return merge_windows(cluster_windows(mask, width, height), overhead_pixels);
}

namespace {

double clamp_unit(double value)
{
    return std::clamp(value, 0.0, 1.0);
}

} // namespace

NormalisedWindow cycles_border(const PixelWindow& window, int width, int height)
{
    const double w = width, h = height;
    return {clamp_unit((window.x0 + 0.25) / w), clamp_unit((window.x1 + 0.25) / w),
            clamp_unit((height - window.y1 + 0.25) / h), clamp_unit((height - window.y0 + 0.25) / h)};
}

NormalisedWindow renderman_crop_window(const PixelWindow& window, int width, int height)
{
    const double w = width, h = height;
    return {clamp_unit((window.x0 - 0.25) / w), clamp_unit((window.x1 - 0.25) / w),
            clamp_unit((window.y0 - 0.25) / h), clamp_unit((window.y1 - 0.25) / h)};
}

NormalisedWindow ndc_data_window(const PixelWindow& window, int width, int height)
{
    const double w = width, h = height;
    return {window.x0 / w, window.x1 / w, (height - window.y1) / h, (height - window.y0) / h};
}

} // namespace modestack::refine
