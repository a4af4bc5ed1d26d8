// core/metrics/image_error: each figure against a closed form worked out by hand
// on exactly representable values, idiff's per-pixel counting, NaN/Inf rules,
// and bit-identical sums for any thread count.
#include "core/metrics/image_error.h"

#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

using namespace modestack::metrics;

namespace {
// Closed forms of the definitions in docs/design.md, "How quality is measured",
// written independently of the library.
double expected_tonemap(double v)
{
    return std::pow(v / (1.0 + v), 1.0 / 2.2);
}
double expected_relative(double x, double r)
{
    return (x - r) * (x - r) / (r * r + 0.01);
}
} // namespace

TEST_CASE("identical images: every error is zero, PSNR is infinite, nothing fails")
{
    std::vector<float> image(7 * 5 * 3);
    for (size_t i = 0; i < image.size(); ++i)
        image[i] = 0.37f * static_cast<float>(i % 11);
    ErrorSums sums = frame_errors(image.data(), image.data(), 35, 3, PixelThresholds{});
    CHECK(sums.pixels == 35);
    CHECK(sums.values == 105);
    CHECK(sums.relative_mse() == 0.0);
    CHECK(sums.mean_absolute() == 0.0);
    CHECK(sums.max_absolute == 0.0);
    CHECK(sums.pixels_failing == 0);
    CHECK(sums.percent_failing() == 0.0);
    CHECK(std::isinf(sums.psnr()));
    CHECK(sums.psnr() > 0);
}

TEST_CASE("a known perturbation gives the closed-form relMSE, PSNR and absolute errors")
{
    // 10 pixels x 3 channels, reference 0.5 everywhere; pixels 0..3 are off by
    // +0.125 in every channel (exact in float), the others exact.
    const int pixels = 10, channels = 3;
    std::vector<float> reference(pixels * channels, 0.5f), test = reference;
    for (int p = 0; p < 4; ++p)
        for (int c = 0; c < channels; ++c)
            test[p * channels + c] = 0.625f;
    ErrorSums sums =
        frame_errors(test.data(), reference.data(), pixels, channels, PixelThresholds{0.1, 0.01});

    double share = 4.0 / 10.0;
    double relative = share * expected_relative(0.625, 0.5); // 0.4 x 0.015625 / 0.26
    CHECK(relative == doctest::Approx(0.4 * 0.015625 / 0.26).epsilon(1e-15));
    CHECK(sums.relative_mse() == doctest::Approx(relative).epsilon(1e-12));
    double tonemapped_difference = expected_tonemap(0.625) - expected_tonemap(0.5);
    double psnr = 10.0 * std::log10(1.0 / (share * tonemapped_difference * tonemapped_difference));
    CHECK(sums.psnr() == doctest::Approx(psnr).epsilon(1e-12));
    CHECK(std::abs(sums.psnr() - psnr) < 1e-6);
    CHECK(sums.mean_absolute() == doctest::Approx(share * 0.125).epsilon(1e-15));
    CHECK(sums.max_absolute == 0.125);
    CHECK(sums.pixels_failing == 4);
    CHECK(sums.pixels_warning == 4);
    CHECK(sums.percent_failing() == doctest::Approx(40.0));
}

TEST_CASE("relMSE weighs dark reference pixels by 1 / (r^2 + 0.01)")
{
    // The same absolute error 0.25 on a black and on a bright reference.
    std::vector<float> reference{0.0f, 4.0f}, test{0.25f, 4.25f};
    ErrorSums sums = frame_errors(test.data(), reference.data(), 2, 1, PixelThresholds{});
    double expected = 0.5 * (0.0625 / 0.01 + 0.0625 / 16.01);
    CHECK(sums.relative_mse() == doctest::Approx(expected).epsilon(1e-12));
}

TEST_CASE("a pixel fails when any one of its channels is over the threshold (idiff), strictly over")
{
    const int pixels = 6, channels = 4;
    std::vector<float> reference(pixels * channels, 1.0f), test = reference;
    test[2 * channels + 3] = 1.5f;   // pixel 2, last channel: over both thresholds
    test[4 * channels + 1] = 1.25f;  // pixel 4: over warn only
    test[5 * channels + 0] = 1.375f; // pixel 5: exactly at the fail threshold: not over it
    ErrorSums sums =
        frame_errors(test.data(), reference.data(), pixels, channels, PixelThresholds{0.375, 0.125});
    CHECK(sums.pixels_failing == 1);
    CHECK(sums.pixels_warning == 3);
    CHECK(sums.percent_failing() == doctest::Approx(100.0 / 6.0));
    CHECK(sums.percent_warning() == doctest::Approx(50.0));
    CHECK(sums.max_absolute == 0.5);
}

TEST_CASE("tonemap: x/(1+x) with gamma 1/2.2, clipped to [0, 1]")
{
    CHECK(tonemap_for_psnr(0.0) == 0.0);
    CHECK(tonemap_for_psnr(-3.0) == 0.0);
    CHECK(tonemap_for_psnr(1.0) == doctest::Approx(std::pow(0.5, 1.0 / 2.2)));
    CHECK(tonemap_for_psnr(std::numeric_limits<double>::infinity()) == 1.0);
    CHECK(tonemap_for_psnr(1e30) <= 1.0);
    CHECK(std::isnan(tonemap_for_psnr(std::nan(""))));
    // Monotonic: brighter stays brighter.
    double previous = 0.0;
    for (double v = 0.01; v < 100.0; v *= 1.7) {
        CHECK(tonemap_for_psnr(v) > previous);
        previous = tonemap_for_psnr(v);
    }
}

TEST_CASE("NaN/Inf: the same non-finite value is no error, a mismatch is an infinite, failing error")
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> reference{nan, inf, 0.5f, 0.5f}, same{nan, inf, 0.5f, 0.5f},
        wrong{0.5f, inf, nan, 0.5f};
    ErrorSums matching = frame_errors(same.data(), reference.data(), 4, 1, PixelThresholds{});
    CHECK(matching.non_finite == 0);
    CHECK(matching.relative_mse() == 0.0);
    CHECK(matching.pixels_failing == 0);

    ErrorSums mismatched = frame_errors(wrong.data(), reference.data(), 4, 1, PixelThresholds{});
    CHECK(mismatched.non_finite == 2);
    CHECK(mismatched.pixels_failing == 2);
    CHECK(std::isinf(mismatched.max_absolute));
    CHECK(std::isinf(mismatched.relative_mse()));
    // The tonemapped difference of a mismatch is the largest possible, 1: PSNR stays finite.
    CHECK(mismatched.psnr() == doctest::Approx(10.0 * std::log10(4.0 / 2.0)));
}

TEST_CASE("an empty image compares as no error")
{
    ErrorSums sums = frame_errors(nullptr, nullptr, 0, 3, PixelThresholds{});
    CHECK(sums.pixels == 0);
    CHECK(sums.relative_mse() == 0.0);
    CHECK(sums.percent_failing() == 0.0);
    CHECK(std::isnan(sums.mean_flicker()));
}

TEST_CASE("frame_errors and add_flicker are bit-identical for 1 and 4 threads and match a plain sum")
{
    // 257 x 89 pixels: several chunks, the last one partial.
    const int pixels = 257 * 89, channels = 3;
    std::vector<float> reference(pixels * channels), test(pixels * channels), previous_reference,
        previous_test;
    unsigned state = 12345;
    auto next = [&state] {
        state = state * 1664525u + 1013904223u;
        return static_cast<float>(state >> 8) / 16777216.0f;
    };
    for (size_t i = 0; i < reference.size(); ++i) {
        reference[i] = 2.0f * next();
        test[i] = reference[i] + 0.2f * (next() - 0.5f);
    }
    previous_reference = reference;
    previous_test = test;
    for (size_t i = 0; i < reference.size(); ++i)
        previous_test[i] += 0.1f * (next() - 0.5f);

    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        ErrorSums sums =
            frame_errors(test.data(), reference.data(), pixels, channels, PixelThresholds{0.05, 0.01});
        add_flicker(test.data(), reference.data(), previous_test.data(), previous_reference.data(),
                    static_cast<std::int64_t>(test.size()), sums);
        return sums;
    };
    ErrorSums one = run(1), four = run(4);
    CHECK(std::memcmp(&one.squared_relative, &four.squared_relative, sizeof(double)) == 0);
    CHECK(std::memcmp(&one.squared_tonemapped, &four.squared_tonemapped, sizeof(double)) == 0);
    CHECK(std::memcmp(&one.absolute, &four.absolute, sizeof(double)) == 0);
    CHECK(std::memcmp(&one.flicker, &four.flicker, sizeof(double)) == 0);
    CHECK(one.pixels_failing == four.pixels_failing);

    long double relative = 0, flicker = 0;
    for (size_t i = 0; i < test.size(); ++i) {
        relative += expected_relative(test[i], reference[i]);
        double change = (double(test[i]) - previous_test[i]) - (double(reference[i]) - previous_reference[i]);
        double mean = 0.5 * (double(reference[i]) + previous_reference[i]);
        flicker += change * change / (mean * mean + 0.01);
    }
    CHECK(one.relative_mse() == doctest::Approx(double(relative / test.size())).epsilon(1e-12));
    CHECK(one.mean_flicker() == doctest::Approx(double(flicker / test.size())).epsilon(1e-12));
    CHECK(one.relative_mse() > 0.0);
}
