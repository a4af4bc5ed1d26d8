// The mode filter's weights (core/denoise/filter_weights.h, guided_filter.h): the
// vectorisable exp against the library's, and the row-wise guided filter against
// its definition evaluated window by window in double, on an RGB band with
// feature rows, clipped at every edge, two candidates at once.
#include "core/denoise/filter_weights.h"
#include "core/denoise/mode_filter.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;

TEST_CASE("filter weights: weight_exp is exp within 2e-7 relative, 1 at 0 and 0 below -87")
{
    double largest = 0;
    for (int i = 0; i <= 870000; ++i) {
        const float x = -0.0001f * static_cast<float>(i);
        const double exact = std::exp(static_cast<double>(x));
        largest = std::max(largest, std::abs(weight_exp(x) - exact) / exact);
    }
    MESSAGE("largest relative error on [-87, 0]: " << largest);
    CHECK(largest < 2e-7);
    CHECK(weight_exp(0.0f) == 1.0f);
    CHECK(weight_exp(-87.5f) == 0.0f);
    CHECK(weight_exp(-INFINITY) == 0.0f);
    CHECK(weight_exp(1.0f) == doctest::Approx(std::exp(1.0)).epsilon(1e-6));
}

TEST_CASE("filter weights: the guided filter is its clipped cross-bilateral window, with range and feature terms")
{
    // Rows 2-13 of a 29 × 17 RGB band, 3 modes: c_1 guides, mode 2 has a range
    // term, mode 3 range and feature terms (2 feature channels).
    const int width = 29, height = 17, channels = 3, features = 2, valid_y0 = 2, valid_y1 = 14, modes = 3;
    const std::int64_t plane = std::int64_t(width) * height, samples = plane * channels;
    std::mt19937 generator(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<float> coefficients(static_cast<std::size_t>(samples * modes)), variance(samples), feature(plane * features);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            for (int c = 0; c < channels; ++c) {
                const std::int64_t i = (std::int64_t(y) * width + x) * channels + c;
                coefficients[i] = static_cast<float>((x < 12 ? 3.0 : 7.0) + 0.5 * c + 0.4 * normal(generator));
                for (int j = 1; j < modes; ++j)
                    coefficients[j * samples + i] = static_cast<float>(normal(generator));
                variance[i] = static_cast<float>(0.1 + 0.05 * (x % 3));
            }
            for (int k = 0; k < features; ++k)
                feature[(std::int64_t(y) * width + x) * features + k] = static_cast<float>(y > 8 ? 1.0 + k : 0.2 * k);
        }
    ModeFilterPlan plan;
    plan.candidates = {{0.0, 0.0, 0.0}, {1.5, 2.0, 0.0}, {1.0, 1.5, 0.5}};
    plan.modes.resize(modes);
    plan.modes[1].candidate = 1, plan.modes[2].candidate = 2;
    plan.kept_modes = modes;
    plan.guide_smoothing = 0;  // the guide is c_1 itself
    plan.feature_channels = features;
    const std::int64_t valid = std::int64_t(width) * (valid_y1 - valid_y0) * channels;
    std::vector<float> filtered(static_cast<std::size_t>(valid * modes)), gains;
    filter_coefficients({coefficients.data(), samples, modes, samples}, variance, {width, height, channels}, valid_y0,
                        valid_y1, plan, modes, {filtered.data(), valid, modes, valid}, gains, feature.data());

    double largest_error = 0, largest_gain_error = 0;
    for (int j = 1; j < modes; ++j) {
        const FilterCandidate& candidate = plan.candidates[plan.modes[j].candidate];
        const int radius = static_cast<int>(std::ceil(2.5 * candidate.width));
        for (int y = valid_y0; y < valid_y1; ++y)
            for (int x = 0; x < width; ++x) {
                const std::int64_t p = std::int64_t(y) * width + x;
                double sum = 0, squares = 0, weighted[channels] = {};
                for (int qy = std::max(0, y - radius); qy <= std::min(height - 1, y + radius); ++qy)
                    for (int qx = std::max(0, x - radius); qx <= std::min(width - 1, x + radius); ++qx) {
                        const std::int64_t q = std::int64_t(qy) * width + qx;
                        double range = 0, feature_distance = 0;
                        for (int c = 0; c < channels; ++c) {
                            const double difference = double(coefficients[p * channels + c]) - coefficients[q * channels + c];
                            range += difference * difference / (double(variance[p * channels + c]) + variance[q * channels + c]);
                        }
                        for (int k = 0; k < features; ++k) {
                            const double difference = double(feature[p * features + k]) - feature[q * features + k];
                            feature_distance += difference * difference;
                        }
                        double exponent = -0.5 * ((qx - x) * (qx - x) + (qy - y) * (qy - y)) /
                                          (candidate.width * candidate.width);
                        exponent -= 0.5 * range / (candidate.range * candidate.range * channels);
                        if (candidate.feature_range > 0)
                            exponent -= 0.5 * feature_distance / (candidate.feature_range * candidate.feature_range * features);
                        const double w = std::exp(exponent);
                        sum += w, squares += w * w;
                        for (int c = 0; c < channels; ++c)
                            weighted[c] += w * coefficients[j * samples + q * channels + c];
                    }
                const std::int64_t out_pixel = std::int64_t(y - valid_y0) * width + x;
                for (int c = 0; c < channels; ++c)
                    largest_error = std::max(largest_error,
                                             std::abs(filtered[j * valid + out_pixel * channels + c] - weighted[c] / sum));
                const double gain = gains[static_cast<std::size_t>(j * (valid / channels) + out_pixel)];
                largest_gain_error = std::max(largest_gain_error, std::abs(gain - squares / (sum * sum)) / (squares / (sum * sum)));
            }
    }
    MESSAGE("largest difference from the window: " << largest_error << ", relative of the gain " << largest_gain_error);
    CHECK(largest_error < 2e-6);  // the modes are of unit scale
    CHECK(largest_gain_error < 1e-5);
    // Mode 1 (width 0) is copied.
    for (std::int64_t i = 0; i < valid; ++i)
        REQUIRE(filtered[i] == coefficients[valid_y0 * std::int64_t(width) * channels + i]);
}
