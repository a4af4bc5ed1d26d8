#include "core/denoise/temporal_spread.h"

#include "core/common/error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace modestack::denoise {
namespace {

// P(a, x), the regularized lower incomplete gamma function, by its series (the
// lower tail needed here has x well below a + 1, where it converges fast).
double lower_gamma_regularized(double a, double x)
{
    if (x <= 0)
        return 0;
    double term = 1.0 / a, sum = term;
    for (int k = 1; k < 1000 && term > sum * 1e-17; ++k) {
        term *= x / (a + k);
        sum += term;
    }
    return std::exp(a * std::log(x) - x - std::lgamma(a)) * sum;
}

// The p quantile of χ² with n degrees of freedom, by bisection of P(n/2, x/2).
double chi_squared_quantile(int n, double p)
{
    double low = 0, high = n + 10.0 * std::sqrt(2.0 * n);
    for (int i = 0; i < 200; ++i) {
        const double middle = (low + high) / 2;
        (lower_gamma_regularized(n / 2.0, middle / 2) < p ? low : high) = middle;
    }
    return (low + high) / 2;
}

} // namespace

double spread_bound(int terms)
{
    static const std::array<double, kMostSpreadTerms + 1> bounds = [] {
        std::array<double, kMostSpreadTerms + 1> table{};
        for (int n = 1; n <= kMostSpreadTerms; ++n)
            table[static_cast<size_t>(n)] = n / chi_squared_quantile(n, 1e-3);
        return table;
    }();
    if (terms < 1)
        throw internal_error("spread_bound: no terms");
    return terms <= kMostSpreadTerms ? bounds[static_cast<size_t>(terms)]
                                     : terms / chi_squared_quantile(terms, 1e-3);
}

double lone_sample_reach(SpreadEstimate estimate, int terms)
{
    if (terms < 1)
        throw internal_error("lone_sample_reach: no terms");
    return std::sqrt(2.0 * (estimate == SpreadEstimate::Steady ? terms : terms + 6));
}

void judged_samples(const float* as_read, const float* cleaned, std::int64_t samples, float* judged)
{
    for (std::int64_t i = 0; i < samples; ++i)
        judged[i] = std::max(as_read[i], cleaned[i]);
}

void spread_pair_rows(const lowrank::ImageBandShape& image, int rows_begin, const float* p, const float* q,
                      int row, int end, float* terms)
{
    const int width = image.width, channels = image.channels;
    const std::int64_t row_samples = static_cast<std::int64_t>(width) * channels;
    for (int y = row; y < end; ++y) {
        const std::int64_t offset = (y - rows_begin) * row_samples;
        const float *a = p + offset, *b = q + offset;
        float* out = terms + static_cast<std::int64_t>(y - row) * width;
        for (int x = 0; x < width; ++x) {
            double squares = 0;
            for (int c = 0; c < channels; ++c) {
                const std::int64_t i = static_cast<std::int64_t>(x) * channels + c;
                const double d = static_cast<double>(b[i]) - a[i];
                squares += d * d;
            }
            out[x] = static_cast<float>(squares / (2.0 * channels));
        }
    }
}

void spread_rows(const SpreadWindow& window, int row, int end, float* spread, float* terms)
{
    const int width = window.image.width;
    constexpr int K = kSpreadFrames;
    if (window.frames[K] == nullptr || row < 0 || end > window.image.height || row > end)
        throw internal_error("spread_rows: no judged frame, or rows outside the image");
    // Per side and pixel of a row: the sum over the side's differences (the
    // nearest first) of their terms, and that sum less the side's trend; then
    // the sums of the row's 3 pixels.
    thread_local std::vector<double> sums[2], detrended[2];
    thread_local std::vector<float> made; // one row of a pair's terms
    made.resize(static_cast<size_t>(width));
    for (int y = row; y < end; ++y) {
        int differences[2] = {0, 0};
        for (int side = 0; side < 2; ++side) {
            std::vector<double>& sum = sums[side];
            sum.assign(static_cast<size_t>(width), 0.0);
            for (int step = 0; step < K; ++step) {
                // Left: frames (K − step − 1, K − step); right: (K + step, K + step + 1).
                const int a = side == 0 ? K - step - 1 : K + step;
                if (window.frames[static_cast<size_t>(a)] == nullptr ||
                    window.frames[static_cast<size_t>(a + 1)] == nullptr)
                    break;
                ++differences[side];
                const float* given = window.pair_terms[static_cast<size_t>(a)];
                const float* pair = nullptr;
                if (given != nullptr && a != K - 1 && a != K) {
                    pair = given + static_cast<std::int64_t>(y - window.rows_begin) * width;
                } else {
                    spread_pair_rows(window.image, window.rows_begin, window.frames[static_cast<size_t>(a)],
                                     window.frames[static_cast<size_t>(a + 1)], y, y + 1, made.data());
                    pair = made.data();
                }
                for (int x = 0; x < width; ++x)
                    sum[static_cast<size_t>(x)] += pair[x];
            }
            // Less the trend: Σ(d − d̄)² = Σd² − (Σd)²/m, and Σd is the side's
            // end-to-end difference.
            const int m = differences[side];
            if (m < 2)
                continue;
            const int first = side == 0 ? K - m : K;
            spread_pair_rows(window.image, window.rows_begin, window.frames[static_cast<size_t>(first)],
                             window.frames[static_cast<size_t>(first + m)], y, y + 1, made.data());
            detrended[side].resize(static_cast<size_t>(width));
            for (int x = 0; x < width; ++x)
                detrended[side][static_cast<size_t>(x)] =
                    sum[static_cast<size_t>(x)] - made[static_cast<size_t>(x)] / m;
        }
        const std::int64_t out = static_cast<std::int64_t>(y - row) * width * kSpreadEstimates;
        for (int x = 0; x < width; ++x) {
            const int x0 = std::max(0, x - 1), x1 = std::min(width - 1, x + 1), pixels = x1 - x0 + 1;
            for (const SpreadEstimate estimate : {SpreadEstimate::Steady, SpreadEstimate::Trend}) {
                const bool trend = estimate == SpreadEstimate::Trend;
                double best = std::numeric_limits<double>::infinity();
                int best_terms = 0;
                for (int side = 0; side < 2; ++side) {
                    // Of white noise of variance v, a pixel's sum has the mean m·v
                    // (trend: (m − 1/m)·v, m − 1 degrees of freedom).
                    const int m = differences[side];
                    if (m < (trend ? 2 : 1))
                        continue;
                    const std::vector<double>& from = trend ? detrended[side] : sums[side];
                    double total = 0;
                    for (int u = x0; u <= x1; ++u)
                        total += from[static_cast<size_t>(u)];
                    const double here = std::max(total, 0.0) / (pixels * (trend ? m - 1.0 / m : m));
                    if (here < best)
                        best = here, best_terms = pixels * (trend ? m - 1 : m);
                }
                const std::int64_t i =
                    out + static_cast<std::int64_t>(x) * kSpreadEstimates + static_cast<int>(estimate);
                spread[i] = static_cast<float>(best);
                terms[i] = static_cast<float>(best_terms);
            }
        }
    }
}

} // namespace modestack::denoise
