// The rebuild's lasting misfit (core/denoise/temporal_misfit.h): the
// statistics' exact values on a small case, a lasting offset found on both
// sides and only where the rebuild rates itself no better than the input's
// scatter, the false-alarm rate on noise around a right rebuild, a lone
// firefly never passing, the sides at the shot's ends, and the t quantiles
// against their closed forms and published values.
#include "core/common/error.h"
#include "core/denoise/temporal_misfit.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;

namespace {

constexpr int kWidth = 64, kHeight = 40, kChannels = 3, kWindow = 2 * kMisfitFrames + 1;
constexpr size_t kSamples = static_cast<size_t>(kWidth) * kHeight * kChannels;
constexpr size_t kPixels = static_cast<size_t>(kWidth) * kHeight;

size_t at(int x, int y, int c = 0)
{
    return (static_cast<size_t>(y) * kWidth + x) * kChannels + c;
}

// A window of kWindow frames: inputs `level` + Gaussian noise of standard
// deviation `noise`, rebuilds `level`; frames outside a shot of `shot_frames`
// frames around the judged one (frame `judged` of the shot) are left null.
struct Window {
    std::vector<std::vector<float>> input, rebuilt;
    int judged = kMisfitFrames, shot_frames = 1000;
    Window(float level, float noise, unsigned seed)
        : input(kWindow, std::vector<float>(kSamples)), rebuilt(kWindow, std::vector<float>(kSamples, level))
    {
        std::mt19937 generator(seed);
        std::normal_distribution<float> normal(0.0f, noise > 0 ? noise : 1.0f);
        for (auto& frame : input)
            for (float& value : frame)
                value = noise > 0 ? level + normal(generator) : level;
    }
    std::vector<float> misfit() const
    {
        MisfitWindow window;
        window.image = {kWidth, kHeight, kChannels};
        for (int k = 0; k < kWindow; ++k) {
            const int t = judged + k - kMisfitFrames;
            if (t >= 0 && t < shot_frames)
                window.input[static_cast<size_t>(k)] = input[static_cast<size_t>(k)].data(),
                window.rebuilt[static_cast<size_t>(k)] = rebuilt[static_cast<size_t>(k)].data();
        }
        std::vector<float> values(kPixels * kMisfitValues);
        misfit_rows(window, 0, kHeight, values.data());
        return values;
    }
};

const float* pixel(const std::vector<float>& misfit, int x, int y)
{
    return misfit.data() + (static_cast<size_t>(y) * kWidth + x) * kMisfitValues;
}

} // namespace

TEST_CASE("misfit: each side's mean residual, pooled scatter, frames and degrees of freedom are exact")
{
    Window window(0.5f, 0.0f, 1); // no noise: every residual is set below
    // Pixel (10, 5) and its row neighbours: residuals (the same in every
    // channel) r(q, k) = q-offset + k·0.01 on frame k, so each pixel's mean
    // differs and its scatter about its own mean is that of k·0.01.
    for (int k = 0; k < kWindow; ++k)
        for (int q = 9; q <= 11; ++q)
            for (int c = 0; c < kChannels; ++c)
                window.input[static_cast<size_t>(k)][at(q, 5, c)] = 0.5f + 0.1f * (q - 9) + 0.01f * k;
    const std::vector<float> misfit = window.misfit();
    const float* values = pixel(misfit, 10, 5);
    // Before: frames 0…4, the pixel's residuals 0.1 + 0.01·k: mean 0.12; each
    // pixel's squares about its mean sum to 0.001, over 3·4 degrees of freedom.
    CHECK(values[0] == doctest::Approx(0.12).epsilon(1e-5));
    CHECK(values[1] == doctest::Approx(3 * 0.001 / 12).epsilon(1e-4));
    CHECK(values[2] == 5.0f);
    CHECK(values[3] == 12.0f);
    // After: frames 4…8: mean 0.1 + 0.06.
    CHECK(values[4] == doctest::Approx(0.16).epsilon(1e-5));
    CHECK(values[5] == doctest::Approx(3 * 0.001 / 12).epsilon(1e-4));
    CHECK(values[6] == 5.0f);
    CHECK(values[7] == 12.0f);
    // At the image's left edge the row has two pixels.
    CHECK(pixel(misfit, 0, 5)[3] == 8.0f);
}

TEST_CASE("misfit: a lasting offset of 3 noise widths is found, and asked only where the rebuild rates "
          "itself no better than the input's scatter")
{
    Window window(0.5f, 0.05f, 2);
    for (auto& frame : window.input) // a 4 × 2 patch the rebuild misses by 0.15 in every frame
        for (int y = 10; y < 12; ++y)
            for (int x = 20; x < 24; ++x)
                for (int c = 0; c < kChannels; ++c)
                    frame[at(x, y, c)] += 0.15f;
    const std::vector<float> misfit = window.misfit();
    int found = 0, found_sure = 0;
    for (int y = 10; y < 12; ++y)
        for (int x = 20; x < 24; ++x) {
            found += lasting_misfit(pixel(misfit, x, y), 1.0) ? 1 : 0;
            found_sure += lasting_misfit(pixel(misfit, x, y), 1e-6) ? 1 : 0; // sigma far below the noise
        }
    // t ≈ 0.15·√5 / (0.05/√3) ≈ 11.6 for the channel mean, against a limit
    // of 6.1 at 12 degrees of freedom on either side.
    CHECK(found >= 7);
    CHECK(found_sure == 0);
}

TEST_CASE("misfit: around a right rebuild, noise passes at about the test's rate, and a lone firefly never")
{
    int fired = 0, tests = 0;
    for (unsigned seed = 0; seed < 20; ++seed) {
        Window window(0.5f, 0.1f, 100 + seed);
        const std::vector<float> misfit = window.misfit();
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x, ++tests)
                fired += lasting_misfit(pixel(misfit, x, y), 1e9) ? 1 : 0;
    }
    // 10⁻⁴ of 51 200 pixels is 5: more than 25 would be a test far looser than it says.
    INFO("pixels tested: " << tests << ", passed: " << fired);
    CHECK(fired <= 25);

    Window firefly(0.5f, 0.02f, 3);
    for (int c = 0; c < kChannels; ++c)
        firefly.input[kMisfitFrames][at(30, 20, c)] = 500.0f; // the judged frame's sample, as read
    const std::vector<float> misfit = firefly.misfit();
    for (int x = 29; x <= 31; ++x)
        CHECK_FALSE(lasting_misfit(pixel(misfit, x, 20), 1e9));
}

TEST_CASE("misfit: at the shot's first frame the side before has no degrees of freedom")
{
    Window window(0.5f, 0.1f, 4);
    window.judged = 0;
    const std::vector<float> misfit = window.misfit();
    CHECK(pixel(misfit, 5, 5)[2] == 1.0f); // the judged frame alone
    CHECK(pixel(misfit, 5, 5)[3] == 0.0f);
    CHECK(pixel(misfit, 5, 5)[6] == 5.0f);
    window.judged = 1, window.shot_frames = 2; // a shot of two frames
    const std::vector<float> short_shot = window.misfit();
    CHECK(pixel(short_shot, 5, 5)[3] == 3.0f); // frames 0 and 1 before, 3 pixels
    CHECK(pixel(short_shot, 5, 5)[7] == 0.0f);
}

TEST_CASE("misfit: the t limits match the closed forms and published quantiles")
{
    // ν = 1 (Cauchy): P(|T| > t) = 1 − 2·atan(t)/π.
    CHECK(misfit_limit(1) == doctest::Approx(std::tan(M_PI / 2 * (1 - 0.5e-4))).epsilon(1e-9));
    // ν = 2: P(|T| ≤ t) = t / √(t² + 2).
    const double p = 1 - 0.5e-4;
    CHECK(misfit_limit(2) == doctest::Approx(std::sqrt(2 * p * p / (1 - p * p))).epsilon(1e-9));
    // Student's t upper 0.25·10⁻⁴ quantiles (scipy.stats.t.isf(0.25e-4, ν)).
    CHECK(misfit_limit(4) == doctest::Approx(18.5224).epsilon(1e-5));
    CHECK(misfit_limit(8) == doctest::Approx(7.85065).epsilon(1e-5));
    CHECK(misfit_limit(12) == doctest::Approx(6.14287).epsilon(1e-5));
    CHECK(misfit_limit(1000) == doctest::Approx(4.07339).epsilon(1e-5));
    CHECK_THROWS_AS(misfit_limit(0), Error);
}
