// Noise that repeats from frame to frame (core/denoise/repeating_noise.h): found
// where the same noise is in every frame, not where it is new in every frame
// (Gaussian or heavy-tailed), not in a clean picture's still detail,
// each layer on its own from one read, the frames read spread over the shot.
#include "core/common/progress.h"
#include "core/denoise/engine.h"
#include "core/denoise/repeating_noise.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

constexpr int kWidth = 48, kHeight = 100, kFrames = 20; // 100 rows: two bands of reads

// A lit wall with a soft gradient and a light that brightens over the shot.
float picture(int t, int x, int y)
{
    return (0.3f + 0.004f * x + 0.002f * y) * (1.0f + 0.02f * t);
}

// Noise of pixel (x, y, c) in frame t: `repeat` draws the same numbers every
// frame; `heavy` gives it a 4-spp-like tail (log-normal: mostly a little
// below the mean, now and then a bright sample).
float noise(int t, int x, int y, int c, bool repeat, bool heavy)
{
    std::mt19937 generator(static_cast<unsigned>((((repeat ? 0 : t) * 1009 + y) * 1013 + x) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 1.0f);
    if (heavy)
        return 0.02f * (std::exp(1.5f * normal(generator)) - std::exp(1.125f));
    return 0.05f * normal(generator);
}

// A shot of `layers` RGB layers, layer l's noise repeating where repeat[l].
MemoryShot shot_of(std::vector<bool> repeat, bool heavy = false, float noise_level = 1.0f)
{
    MemoryShot shot;
    const int layers = static_cast<int>(repeat.size());
    shot.size = {kFrames, kWidth, kHeight, 3 * layers};
    for (int t = 0; t < kFrames; ++t) {
        std::vector<float> frame;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int l = 0; l < layers; ++l)
                    for (int c = 0; c < 3; ++c)
                        frame.push_back(picture(t, x, y) +
                                        noise_level * noise(t, x, y, 3 * l + c, repeat[size_t(l)], heavy));
        shot.frames.push_back(frame);
    }
    return shot;
}

} // namespace

TEST_CASE("repeating noise: the same noise in every frame repeats, noise new in every frame does not")
{
    for (bool heavy : {false, true}) {
        CAPTURE(heavy);
        MemoryShot fixed = shot_of({true}, heavy);
        const RepeatingNoise repeated = measure_repeating_noise(fixed, Progress::silent());
        CHECK(repeated.measured);
        CHECK(repeated.repeats);
        // The light's steady change cancels in the second difference: nothing is left in time.
        CHECK(repeated.share > 0.95);
        CHECK(repeated.counted());
        CHECK(repeated.counted_share() == repeated.share);
        // White: as much power 1 pixel apart as 2 apart (the gradient adds next to nothing).
        CHECK(repeated.whiteness == doctest::Approx(1.0).epsilon(0.1));

        MemoryShot fresh = shot_of({false}, heavy);
        const RepeatingNoise renewed = measure_repeating_noise(fresh, Progress::silent());
        CHECK(renewed.measured);
        CHECK_FALSE(renewed.repeats);
        CHECK(renewed.counted_share() == 0.0);
        // Both powers are of one difference of two samples of the same noise: they agree,
        // whatever the noise's shape.
        CHECK(renewed.share < 0.1);
        CHECK(renewed.temporal == doctest::Approx(renewed.spatial).epsilon(0.1));
    }
}

TEST_CASE("repeating noise: a clean picture's still detail is smooth at the pixel scale and does not repeat")
{
    // No noise at all, and a fine pattern the pixel filter has smoothed: it stays
    // from frame to frame, but its power 2 pixels apart is far above 1 apart.
    MemoryShot clean = shot_of({true}, false, 0.0f);
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c)
                    clean.frames[size_t(t)][size_t((y * kWidth + x) * 3 + c)] +=
                        0.1f * std::sin(0.5f * x) * std::cos(0.4f * y);
    const RepeatingNoise detail = measure_repeating_noise(clean, Progress::silent());
    CHECK(detail.share > 0.5); // still, like repeating noise
    CHECK(detail.whiteness < 0.5);
    CHECK_FALSE(detail.repeats);
    CHECK(detail.counted_share() == 0.0);
}

TEST_CASE("repeating noise: each layer on its own from one read, the frames in triples over the shot")
{
    struct Counting : ForwardingSource {
        using ForwardingSource::ForwardingSource;
        std::vector<int> reads = std::vector<int>(kFrames, 0);
        void read_rows(int frame, int row_begin, int row_end, float* destination,
                       PassThroughRows* pass_through) override
        {
            ++reads[size_t(frame)];
            ForwardingSource::read_rows(frame, row_begin, row_end, destination, pass_through);
        }
    };
    MemoryShot shot = shot_of({false, true});
    Counting counted(shot);
    const std::vector<RepeatingNoise> layers =
        measure_repeating_noise(counted, {ChannelGroup{0, 3}, ChannelGroup{3, 3}}, Progress::silent());
    REQUIRE(layers.size() == 2);
    CHECK_FALSE(layers[0].repeats);
    CHECK(layers[1].repeats);
    // Triples at the shot's start, middle and end; each of their frames read once per band of rows.
    const std::vector<int> expected{0, 1, 2, 9, 10, 11, 17, 18, 19};
    CHECK(layers[0].frames == expected);
    CHECK(layers[1].frames == expected);
    const int bands = (kHeight + kRepeatingNoiseBandRows - 1) / kRepeatingNoiseBandRows;
    for (int t = 0; t < kFrames; ++t) {
        CAPTURE(t);
        const bool read = std::find(expected.begin(), expected.end(), t) != expected.end();
        CHECK(counted.reads[size_t(t)] == (read ? bands : 0));
    }
    // Each is what its layer alone gives.
    MemoryShot second = shot_of({true});
    const RepeatingNoise alone = measure_repeating_noise(second, Progress::silent());
    CHECK(layers[1].share == doctest::Approx(alone.share).epsilon(0.05));
}

TEST_CASE(
    "repeating noise: three frames give one triple, a non-finite value is skipped, nothing to measure is 0")
{
    MemoryShot shot = shot_of({true});
    shot.frames.resize(3);
    shot.size.frames = 3;
    shot.frames[1][0] = std::nanf("");
    shot.frames[2][5] = INFINITY;
    const RepeatingNoise three = measure_repeating_noise(shot, Progress::silent());
    CHECK(three.frames == std::vector<int>{0, 1, 2});
    CHECK(three.repeats);
    CHECK(std::isfinite(three.share));

    MemoryShot flat = shot_of({false}, false, 0.0f); // one value everywhere: no power between neighbours
    for (auto& frame : flat.frames)
        std::fill(frame.begin(), frame.end(), 0.25f);
    const RepeatingNoise none = measure_repeating_noise(flat, Progress::silent());
    CHECK(none.spatial == 0.0);
    CHECK(none.share == 0.0);
    CHECK(none.whiteness == 0.0);
    CHECK_FALSE(none.repeats);
}

TEST_CASE("repeating noise: a clean render's rounding, white and the same in every frame, is not noise")
{
    // Repeating and white, but 0.01 % of the picture: what a half float's rounding
    // of a noise-free render looks like.
    MemoryShot rounded = shot_of({true}, false, 0.001f);
    const RepeatingNoise tiny = measure_repeating_noise(rounded, Progress::silent());
    CHECK(tiny.share > 0.5);
    CHECK(tiny.whiteness > 0.5);
    CHECK(tiny.level < kLeastNoiseLevel);
    CHECK_FALSE(tiny.repeats);
    // The same noise 250 times stronger (10 % of the picture, a few spp) is.
    MemoryShot noisy = shot_of({true}, false, 1.0f);
    const RepeatingNoise found = measure_repeating_noise(noisy, Progress::silent());
    CHECK(found.level > kLeastNoiseLevel);
    CHECK(found.repeats);
}

TEST_CASE("repeating noise: the choice counts it only where it is as white as render noise")
{
    RepeatingNoise found;
    found.measured = found.repeats = true;
    found.share = 0.8;
    for (double whiteness : {0.5, 0.89, 0.9, 1.05}) {
        CAPTURE(whiteness);
        found.whiteness = whiteness;
        CHECK(found.counted() == (whiteness >= kCountedWhiteness));
        CHECK(found.counted_share() == (found.counted() ? 0.8 : 0.0));
    }
    found.repeats = false;
    found.whiteness = 1;
    CHECK_FALSE(found.counted());
    CHECK(found.counted_share() == 0.0);
}

TEST_CASE("repeating noise: the mode filter's survey counts it, so the rebuild smooths it away")
{
    // The same Gaussian noise in every frame: it lies in the modes (most of it in
    // the first), not in the residual the survey's noise level comes from. The
    // survey's noise scale of a mode may then exceed kMaximumNoiseScale by what
    // the measured repeating noise can put in one mode.
    MemoryShot shot = shot_of({true});
    Settings settings;
    settings.estimators = parse_estimators("rebuild,input,spatial,nlmeans");
    settings.outliers.fireflies = false; // Gaussian noise has no fireflies to treat
    settings.mode_filter.enabled = true;
    MemorySink sink(shot.size);
    const Report report = run_denoise(shot, sink, settings, Progress::silent());
    REQUIRE(report.repeating_noise.counted());
    REQUIRE_FALSE(report.mode_filter.modes.empty());
    const ModeFilterChoice& first = report.mode_filter.modes.front();
    MESSAGE("first mode: noise scale " << first.noise_scale << ", width " << first.width);
    CHECK(first.noise_scale > kMaximumNoiseScale);
    CHECK(first.width > 0);
    std::vector<std::vector<float>> truth(kFrames);
    for (int t = 0; t < kFrames; ++t)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                truth[size_t(t)].insert(truth[size_t(t)].end(), 3, picture(t, x, y));
    const double noisy = mean_square(shot.frames, truth), output = mean_square(sink.rebuilt, truth);
    MESSAGE("MSE output / input " << output / noisy);
    // A 1.5 px Gaussian keeps about 1/(4π·1.5²) = 3.5 % of white noise.
    CHECK(output < 0.035 * noisy);
}
