#include "core/denoise/temporal_misfit.h"

#include "core/common/error.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace modestack::denoise {
namespace {

constexpr double kSideTail = 0.5e-4; // each side's two-sided tail probability

// P(|T| ≤ t) for Student's t with ν degrees of freedom, by the finite sums of
// Abramowitz & Stegun 26.7.3 (ν odd) and 26.7.4 (ν even), θ = atan(t/√ν).
double t_central(int freedom, double t)
{
    const double theta = std::atan(t / std::sqrt(static_cast<double>(freedom)));
    const double sine = std::sin(theta), cosine_squared = std::cos(theta) * std::cos(theta);
    double term = 1, sum = 1;
    if (freedom % 2 == 0) {
        for (int k = 2; k <= freedom - 2; k += 2)
            term *= cosine_squared * (k - 1) / k, sum += term;
        return sine * sum;
    }
    if (freedom == 1)
        return 2 * theta / M_PI;
    for (int k = 3; k <= freedom - 2; k += 2)
        term *= cosine_squared * (k - 1) / k, sum += term;
    return 2 / M_PI * (theta + sine * std::cos(theta) * sum);
}

// t² limits by degrees of freedom.
const std::array<double, kMostMisfitFreedom + 1>& squared_limits()
{
    static const auto table = [] {
        std::array<double, kMostMisfitFreedom + 1> limits{};
        for (int freedom = 1; freedom <= kMostMisfitFreedom; ++freedom)
            limits[static_cast<size_t>(freedom)] = misfit_limit(freedom) * misfit_limit(freedom);
        return limits;
    }();
    return table;
}

} // namespace

double misfit_limit(int freedom)
{
    if (freedom < 1)
        throw internal_error("misfit_limit: no degrees of freedom");
    double low = 0, high = 1e7; // the Cauchy (ν = 1) quantile is about 1.3·10⁴
    for (int i = 0; i < 200; ++i) {
        const double middle = (low + high) / 2;
        (1 - t_central(freedom, middle) > kSideTail ? low : high) = middle;
    }
    return (low + high) / 2;
}

void misfit_rows(const MisfitWindow& window, int row, int end, float* misfit)
{
    const int width = window.image.width, channels = window.image.channels;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    const double per_channel = 1.0 / channels;
    constexpr int judged = kMisfitFrames, side_frames = kMisfitFrames + 1;
    // Per row, each pixel's channel-mean residual in each frame of the window
    // once, then per side each pixel's mean and squared deviations once: the
    // row neighbours pool them (the same sums in the same order as pixel by
    // pixel, a third of the work).
    std::vector<double> residuals(static_cast<std::size_t>(2 * judged + 1) * width);
    std::vector<double> means(static_cast<std::size_t>(width));
    std::vector<double> squares(static_cast<std::size_t>(width) * side_frames);
    // Per side, the frames of the window that are in the shot.
    std::array<std::array<int, side_frames>, 2> present{};
    std::array<int, 2> present_count{};
    for (int side = 0; side < 2; ++side)
        for (int k = side == 0 ? 0 : judged; k <= (side == 0 ? judged : 2 * judged); ++k)
            if (window.input[static_cast<size_t>(k)] != nullptr &&
                window.rebuilt[static_cast<size_t>(k)] != nullptr)
                present[static_cast<size_t>(side)]
                       [static_cast<size_t>(present_count[static_cast<size_t>(side)]++)] = k;
    for (int y = row; y < end; ++y) {
        const std::int64_t offset = (y - window.rows_begin) * row_samples;
        for (int k = 0; k <= 2 * judged; ++k) {
            const float *input = window.input[static_cast<size_t>(k)],
                        *rebuilt = window.rebuilt[static_cast<size_t>(k)];
            if (input == nullptr || rebuilt == nullptr)
                continue;
            double* out = residuals.data() + static_cast<std::size_t>(k) * width;
            for (int x = 0; x < width; ++x) {
                double residual = 0;
                for (int c = 0; c < channels; ++c) {
                    const std::int64_t i = offset + static_cast<std::int64_t>(x) * channels + c;
                    residual += static_cast<double>(input[i]) - rebuilt[i];
                }
                out[x] = residual * per_channel;
            }
        }
        for (int side = 0; side < 2; ++side) {
            const std::array<int, side_frames>& frames = present[static_cast<size_t>(side)];
            const int n = present_count[static_cast<size_t>(side)];
            for (int x = 0; x < width; ++x) {
                double mean = 0;
                for (int i = 0; i < n; ++i)
                    mean += residuals[static_cast<std::size_t>(frames[static_cast<size_t>(i)]) * width + x];
                mean = n > 0 ? mean / n : 0.0;
                means[static_cast<std::size_t>(x)] = mean;
                for (int i = 0; i < n; ++i) {
                    const double deviation =
                        residuals[static_cast<std::size_t>(frames[static_cast<size_t>(i)]) * width + x] -
                        mean;
                    squares[static_cast<std::size_t>(x) * side_frames + i] = deviation * deviation;
                }
            }
            for (int x = 0; x < width; ++x) {
                double scatter = 0;
                int freedom = 0;
                for (int q = std::max(0, x - 1); q <= std::min(width - 1, x + 1); ++q) {
                    for (int i = 0; i < n; ++i)
                        scatter += squares[static_cast<std::size_t>(q) * side_frames + i];
                    freedom += std::max(n - 1, 0);
                }
                float* values = misfit + (static_cast<std::int64_t>(y - row) * width + x) * kMisfitValues +
                                side * (kMisfitValues / 2);
                values[0] = static_cast<float>(means[static_cast<std::size_t>(x)]);
                values[1] = freedom > 0 ? static_cast<float>(scatter / freedom) : 0.0f;
                values[2] = static_cast<float>(n);
                values[3] = static_cast<float>(freedom);
            }
        }
    }
}

bool lasting_misfit(const float* misfit, double rebuilt_variance)
{
    const auto& limits = squared_limits();
    for (int side = 0; side < 2; ++side) {
        const float* values = misfit + side * (kMisfitValues / 2);
        const double mean = values[0], scatter = values[1];
        const int freedom = static_cast<int>(values[3]);
        if (freedom < 1 || rebuilt_variance < scatter)
            continue;
        // t² = mean²·n / s² beyond its limit, without a division (s² may be 0).
        if (mean * mean * values[2] > limits.at(static_cast<size_t>(freedom)) * scatter)
            return true;
    }
    return false;
}

} // namespace modestack::denoise
