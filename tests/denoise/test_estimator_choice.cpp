// The per-pixel choice among estimators (core/denoise/estimator_choice.h) on
// synthetic shots where each estimator must win: a static low-rank shot keeps
// the rebuild, a sharp shadow that sweeps is taken from the spatial estimates
// and the input, a noise-free input is taken as it is; the output is never worse
// than the input in any frame of a shot with a planted transient, sigma follows
// the true error, and the bits do not depend on threads or on streaming.
#include "core/common/error.h"
#include "core/denoise/band_plan.h"
#include "core/denoise/engine.h"
#include "core/denoise/temporal_misfit.h"
#include "core/denoise/temporal_spread.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// A lit wall (a smooth gradient, constant over time, so rank 1) with, optionally,
// a dark bar's shadow that moves `speed` pixels per frame (sharp edges: no few
// modes follow it) and a bright square present in frames [transient_first,
// transient_first + 3) only. `truth` receives the noise-free frames.
MemoryShot wall_shot(int frames, int speed, int transient_first, float noise, unsigned seed,
                     std::vector<std::vector<float>>& truth, int height = 48)
{
    const int width = 64;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    truth.clear();
    for (int t = 0; t < frames; ++t) {
        std::vector<float> clean(static_cast<size_t>(width) * height * 3), noisy(clean.size());
        const int bar = speed > 0 ? (5 + speed * t) % width : -100;
        const bool transient = transient_first >= 0 && t >= transient_first && t < transient_first + 3;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    float value = 0.6f + 0.4f * x / width + 0.1f * c;
                    if (x >= bar && x < bar + 8)
                        value *= 0.15f; // the shadow
                    if (transient && x >= 40 && x < 52 && y >= 16 && y < 28)
                        value = 2.5f; // the object
                    const size_t i = (static_cast<size_t>(y) * width + x) * 3 + c;
                    clean[i] = value;
                    noisy[i] = value + noise * std::sqrt(value) * normal(generator);
                }
        truth.push_back(clean);
        shot.frames.push_back(noisy);
    }
    return shot;
}

Settings choice_settings()
{
    Settings settings;
    settings.estimators = parse_estimators("rebuild,input,spatial,nlmeans");
    settings.outliers.fireflies = false; // Gaussian noise has no fireflies to treat
    return settings;
}

struct Run {
    Report report;
    MemorySink sink;
};

Run run(MemoryShot& shot, const Settings& settings)
{
    MemorySink sink(shot.size);
    Report report = run_denoise(shot, sink, settings, Progress::silent());
    return {report, sink};
}

// The shot denoised with `settings` without the choice (first) and with it.
std::pair<Run, Run> plain_and_chosen(MemoryShot& shot, const Settings& settings = choice_settings())
{
    Settings rebuild_only = settings;
    rebuild_only.estimators = {};
    return {run(shot, rebuild_only), run(shot, settings)};
}

double frame_mse(const std::vector<float>& a, const std::vector<float>& b)
{
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i)
        sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    return sum / a.size();
}

double share(const Report& report, Estimator estimator)
{
    std::int64_t won = 0, all = 0;
    for (const ChoiceCounts& counts : report.estimator_choice)
        for (int k = 0; k < kEstimators; ++k) {
            all += counts.pixels[k];
            won += k == static_cast<int>(estimator) ? counts.pixels[k] : 0;
        }
    return static_cast<double>(won) / all;
}

} // namespace

TEST_CASE("estimators: the list is parsed, and a bad entry is a usage error naming it")
{
    CHECK_FALSE(parse_estimators("rebuild").enabled());
    CHECK(parse_estimators("rebuild,input").input);
    CHECK(parse_estimators("spatial").spatial);
    CHECK(parse_estimators("rebuild,nlmeans").non_local);
    CHECK(parse_estimators("nlmeans").enabled());
    try {
        parse_estimators("rebuild,median");
        FAIL("no error");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::Usage);
        CHECK(std::string(error.what()).find("'median'") != std::string::npos);
    }
}

TEST_CASE("estimators: a static shot keeps the rebuild, and its error does not grow")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(24, 0, -1, 0.1f, 1, truth);
    const auto [plain, chosen] = plain_and_chosen(shot);
    REQUIRE(chosen.report.estimator_choice.size() == 24);
    const double kept = share(chosen.report, Estimator::Rebuild);
    MESSAGE("rebuild share " << kept << ", mse " << mean_square(chosen.sink.rebuilt, truth) << " against "
                             << mean_square(plain.sink.rebuilt, truth));
    CHECK(kept > 0.85); // where it switches, a blur of this smooth wall is as good
    CHECK(mean_square(chosen.sink.rebuilt, truth) <= 1.02 * mean_square(plain.sink.rebuilt, truth));
}

TEST_CASE(
    "estimators: a shadow that sweeps is taken from the input's spatial estimates, never worse than the "
    "input in any frame")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(24, 3, -1, 0.1f, 2, truth);
    const auto [plain, chosen] = plain_and_chosen(shot);
    const double noisy = mean_square(shot.frames, truth), rebuilt = mean_square(plain.sink.rebuilt, truth),
                 output = mean_square(chosen.sink.rebuilt, truth);
    const double spatial = share(chosen.report, Estimator::Gauss1) + share(chosen.report, Estimator::Gauss2);
    MESSAGE("mse noisy " << noisy << ", rebuild " << rebuilt << ", chosen " << output << "; spatial share "
                         << spatial);
    CHECK(rebuilt > noisy); // the temporal model fails here
    CHECK(output < 0.7 * noisy);
    CHECK(spatial > 0.3);
    for (int t = 0; t < shot.size.frames; ++t) {
        CAPTURE(t);
        CHECK(frame_mse(chosen.sink.rebuilt[t], truth[t]) < frame_mse(shot.frames[t], truth[t]));
    }
    // Sigma follows the error it describes: RMS(error) / RMS(sigma) near 1.
    double error = 0, sigma = 0;
    for (int t = 0; t < shot.size.frames; ++t)
        for (size_t i = 0; i < truth[t].size(); ++i) {
            const double e = chosen.sink.rebuilt[t][i] - truth[t][i];
            error += e * e, sigma += double(chosen.sink.sigma[t][i]) * chosen.sink.sigma[t][i];
        }
    MESSAGE("RMS(error) / RMS(sigma) = " << std::sqrt(error / sigma));
    CHECK(std::sqrt(error / sigma) > 0.7);
    CHECK(std::sqrt(error / sigma) < 1.4);
}

TEST_CASE("estimators: a noise-free input is taken as it is where the rebuild misses it")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(24, 3, -1, 0.0f, 3, truth);
    const auto [plain, chosen] = plain_and_chosen(shot);
    const double rebuilt = mean_square(plain.sink.rebuilt, truth),
                 output = mean_square(chosen.sink.rebuilt, truth);
    MESSAGE("mse rebuild " << rebuilt << ", chosen " << output << "; input share "
                           << share(chosen.report, Estimator::Input));
    CHECK(share(chosen.report, Estimator::Input) > 0.1);
    CHECK(output < 0.05 * rebuilt);
}

TEST_CASE("estimators: a planted transient is never worse than the input, in its frames or its region")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(24, 0, 10, 0.1f, 4, truth);
    // One mode: the rebuild misses the object, as when a rank rule keeps no mode for it.
    Settings settings = choice_settings();
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 1;
    const auto [plain, chosen] = plain_and_chosen(shot, settings);
    for (int t = 10; t < 13; ++t) {
        CAPTURE(t);
        double noisy = 0, rebuilt = 0, output = 0;
        for (int y = 16; y < 28; ++y)
            for (int x = 40; x < 52; ++x)
                for (int c = 0; c < 3; ++c) {
                    const size_t i = (static_cast<size_t>(y) * 64 + x) * 3 + c;
                    const double clean = truth[t][i];
                    noisy += (shot.frames[t][i] - clean) * (shot.frames[t][i] - clean);
                    rebuilt += (plain.sink.rebuilt[t][i] - clean) * (plain.sink.rebuilt[t][i] - clean);
                    output += (chosen.sink.rebuilt[t][i] - clean) * (chosen.sink.rebuilt[t][i] - clean);
                }
        MESSAGE("object region: noisy " << noisy << ", rebuild " << rebuilt << ", chosen " << output);
        CHECK(rebuilt > noisy);
        CHECK(output <= noisy);
    }
    for (int t = 0; t < shot.size.frames; ++t) {
        CAPTURE(t);
        CHECK(frame_mse(chosen.sink.rebuilt[t], truth[t]) < frame_mse(shot.frames[t], truth[t]));
    }
}

TEST_CASE("estimators: streamed and kept shots, 1 and 2 threads give the same bits")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(16, 3, 6, 0.1f, 5, truth, 240); // tall enough to stream
    auto run_with = [&](std::int64_t memory, int threads) {
        Settings settings = choice_settings();
        settings.max_memory_bytes = memory;
        MemorySink sink(shot.size);
        Report report;
        tbb::task_arena arena(threads);
        arena.execute([&] { report = run_denoise(shot, sink, settings, Progress::silent()); });
        return Run{report, sink};
    };
    const Run whole = run_with(std::int64_t(1) << 30, 2);
    CHECK(whole.report.plan.in_memory);
    // Smaller budgets: the shot kept with pass 2 in windows, then streamed in
    // bands, then streamed with pass 2 in bands shorter than a Gram chunk. Once
    // it streams, the budget halves: on this shot short bands fit from about
    // 0.65 down to 0.35 of the first streamed budget (measured), so one run
    // reaches them.
    bool windowed = false, streamed = false, short_bands = false;
    for (std::int64_t memory = 12'000'000; memory > 200'000 && !short_bands;
         memory = streamed ? memory / 2 : memory * 9 / 10) {
        Report report;
        try {
            const Run part = run_with(memory, memory % 2 ? 1 : 2);
            report = part.report;
            if (report.plan.band_rows == shot.size.height)
                continue;
            CAPTURE(memory);
            CHECK(part.sink.rebuilt == whole.sink.rebuilt);
            CHECK(part.sink.sigma == whole.sink.sigma);
            (report.plan.in_memory ? windowed : streamed) = true;
            if (report.plan.halo_band_rows < report.plan.band_rows) {
                CHECK(report.plan.band_rows == kChunkRows);
                short_bands = true;
            }
        } catch (const Error&) { // too small for a band
            break;
        }
    }
    CHECK(windowed);
    CHECK(streamed);
    CHECK(short_bands);
    const Run single = run_with(std::int64_t(1) << 30, 1);
    CHECK(single.sink.rebuilt == whole.sink.rebuilt);
    CHECK(single.sink.sigma == whole.sink.sigma);
}

TEST_CASE("estimators: with --non-negative no chosen value is negative, though the input has negatives")
{
    std::vector<std::vector<float>> truth;
    MemoryShot shot = wall_shot(16, 3, -1, 0.1f, 6, truth);
    for (std::vector<float>& frame : shot.frames) // dark: the noise dips below zero
        for (float& value : frame)
            value = 0.1f * value - 0.05f;
    Settings settings = choice_settings();
    settings.non_negative = NonNegativeMode::Clamp;
    const Run chosen = run(shot, settings);
    bool input_negative = false;
    for (const std::vector<float>& frame : shot.frames)
        input_negative |= *std::min_element(frame.begin(), frame.end()) < 0.0f;
    REQUIRE(input_negative);
    CHECK(share(chosen.report, Estimator::Rebuild) < 1.0); // something else was taken somewhere
    for (const std::vector<float>& frame : chosen.sink.rebuilt)
        CHECK(*std::min_element(frame.begin(), frame.end()) >= 0.0f);
}

namespace {

// One frame for choose_estimators itself: a lit wall (0.5) with Gaussian noise
// of standard deviation `noise`, whose rebuild is the noise-free wall; the
// shot's pooled noise is `shot_noise` (by default the frame's), and
// noise_factor says how this frame's compares (frame_noise.h).
// Returns the frame's planes; the caller changes them.
struct WallFrame {
    int width = 64, height = 48, channels = 3;
    std::vector<float> input, rebuilt, sigma, noise_scale;
    double noise_factor = 1;
    double repeating_share = 0; // of the noise, repeating from frame to frame (repeating_noise.h)
    bool noise_repeats = false; // found to repeat, whether counted or not
    double uncounted_share = 0; // repeating where the risks do not count it (sigma does)
    std::vector<float> spread, spread_terms; // the per-pixel test's, when set
    std::vector<float> misfit;               // the residual's statistics in time, when set
    WallFrame(float noise, unsigned seed, float shot_noise = 0)
    {
        const size_t samples = static_cast<size_t>(width) * height * channels;
        std::mt19937 generator(seed);
        std::normal_distribution<float> normal(0.0f, noise);
        rebuilt.assign(samples, 0.5f), sigma.assign(samples, 0.2f * noise);
        const float pooled = shot_noise > 0 ? shot_noise : noise;
        std::vector<float> noise_variance(samples, pooled * pooled);
        noise_scale.resize(samples / channels);
        noise_scale_rows(noise_variance.data(), samples / channels, channels, noise_scale.data());
        input.resize(samples);
        for (size_t i = 0; i < samples; ++i)
            input[i] = 0.5f + normal(generator);
    }
    size_t at(int x, int y, int c = 0) const { return (static_cast<size_t>(y) * width + x) * channels + c; }
    // The estimator taken at each pixel, with or without the noise scale (the one-sided test).
    std::vector<std::uint8_t> choose(bool with_noise_scale, std::vector<float>* values = nullptr,
                                     const std::string& estimators = "rebuild,input,spatial",
                                     std::vector<float>* sigma_of_values = nullptr) const
    {
        ChoiceFrame frame;
        frame.image = {width, height, channels};
        frame.input = input.data(), frame.input_begin = 0, frame.input_end = height;
        frame.rebuilt = rebuilt.data(), frame.sigma = sigma.data(), frame.leverage = 0.05;
        frame.noise_scale = with_noise_scale ? noise_scale.data() : nullptr;
        frame.noise_factor = noise_factor;
        frame.repeating_share = repeating_share;
        frame.noise_repeats = noise_repeats;
        frame.uncounted_share = uncounted_share;
        frame.rebuilt_begin = 0, frame.rebuilt_end = height;
        if (!spread.empty())
            frame.spread = spread.data(), frame.spread_terms = spread_terms.data(), frame.spread_begin = 0;
        if (!misfit.empty())
            frame.misfit = misfit.data(), frame.misfit_begin = 0;
        std::vector<float> chosen_values(input.size()), chosen_sigma(input.size());
        std::vector<std::uint8_t> chosen(static_cast<size_t>(width) * height);
        choose_estimators(parse_estimators(estimators), frame, 0, height, chosen_values.data(),
                          chosen_sigma.data(), chosen.data());
        if (values)
            *values = chosen_values;
        if (sigma_of_values)
            *sigma_of_values = chosen_sigma;
        return chosen;
    }
};

} // namespace

TEST_CASE(
    "estimators: a sliver of shadow the rebuild fills with light is taken from the input, a firefly is not")
{
    WallFrame wall(0.02f, 11);
    // A 1 × 3 pixel sliver of shadow (the input is 0 there: no light reaches it)
    // that the rebuild fills with the wall's 0.5, and a firefly elsewhere that
    // the rebuild rightly leaves out. Each is too narrow for the 7×7 window test.
    const int sliver_x = 20, firefly_x = 44, firefly_y = 30;
    for (int y = 20; y < 23; ++y)
        for (int c = 0; c < 3; ++c)
            wall.input[wall.at(sliver_x, y, c)] = 0.0f;
    for (int c = 0; c < 3; ++c)
        wall.input[wall.at(firefly_x, firefly_y, c)] = 6.0f;
    const std::vector<std::uint8_t> window_only = wall.choose(false);
    std::vector<float> values;
    const std::vector<std::uint8_t> with_test = wall.choose(true, &values);
    auto taken = [&](const std::vector<std::uint8_t>& chosen, int x, int y) {
        return static_cast<Estimator>(chosen[static_cast<size_t>(y) * wall.width + x]);
    };
    for (int y = 20; y < 23; ++y) {
        CAPTURE(y);
        CHECK(taken(window_only, sliver_x, y) == Estimator::Rebuild); // the window test's blind spot
        CHECK(taken(with_test, sliver_x, y) != Estimator::Rebuild);
        CHECK(values[wall.at(sliver_x, y)] < 0.25f); // the shadow, not the light seen in other frames
    }
    CHECK(taken(with_test, firefly_x, firefly_y) == Estimator::Rebuild);
    CHECK(values[wall.at(firefly_x, firefly_y)] == doctest::Approx(0.5f));
}

TEST_CASE("estimators: non-local means only replaces a candidate where the rebuild was rejected, keeps its "
          "sigma, and is nearer the truth where it does")
{
    WallFrame wall(0.1f, 3);
    // A hard shadow (0.075, the wall's 0.5 × 0.15) over columns [24, 40) that the
    // rebuild fills with the wall's light, as where a key light moves.
    auto truth = [](int x) { return x >= 24 && x < 40 ? 0.075f : 0.5f; };
    for (int y = 0; y < wall.height; ++y)
        for (int x = 24; x < 40; ++x)
            for (int c = 0; c < 3; ++c)
                wall.input[wall.at(x, y, c)] += 0.075f - 0.5f;
    std::vector<float> without_values, with_values, without_sigma, with_sigma;
    const auto without = wall.choose(true, &without_values, "rebuild,input,spatial", &without_sigma);
    const auto with = wall.choose(true, &with_values, "rebuild,input,spatial,nlmeans", &with_sigma);
    int replaced = 0;
    double edge_without = 0, edge_with = 0, replaced_without = 0, replaced_with = 0;
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x) {
            const size_t pixel = static_cast<size_t>(y) * wall.width + x;
            if (static_cast<Estimator>(with[pixel]) == Estimator::NonLocal) {
                ++replaced;
                CHECK(static_cast<Estimator>(without[pixel]) != Estimator::Rebuild);
                for (int c = 0; c < 3; ++c) {
                    CHECK(with_sigma[wall.at(x, y, c)] == without_sigma[wall.at(x, y, c)]);
                    const double a = without_values[wall.at(x, y, c)] - truth(x),
                                 b = with_values[wall.at(x, y, c)] - truth(x);
                    replaced_without += a * a, replaced_with += b * b;
                }
            } else {
                CHECK(with[pixel] == without[pixel]);
                CHECK(with_values[wall.at(x, y)] == without_values[wall.at(x, y)]);
            }
            if (y >= 8 && y < 40 && (x == 23 || x == 24 || x == 39 || x == 40))
                for (int c = 0; c < 3; ++c) {
                    const double a = without_values[wall.at(x, y, c)] - truth(x),
                                 b = with_values[wall.at(x, y, c)] - truth(x);
                    edge_without += a * a, edge_with += b * b;
                }
        }
    CHECK(replaced > 0);
    CAPTURE(replaced_without);
    CAPTURE(replaced_with);
    CAPTURE(edge_without);
    CAPTURE(edge_with);
    CHECK(replaced_with < 0.8 * replaced_without);
    CHECK(edge_with < edge_without); // the shadow's edge columns
}

TEST_CASE("estimators: noise that repeats, which the rebuild keeps whole, is counted and blurred away, and "
          "sigma says how much is left")
{
    // The rebuild kept the frame's noise whole (it is the same in every frame), so
    // the residual shows none of it: counted as noise only through the share.
    WallFrame wall(0.05f, 7);
    wall.rebuilt = wall.input;
    auto mean_square = [&](const std::vector<float>& values) {
        double sum = 0;
        for (float value : values)
            sum += (value - 0.5) * (value - 0.5);
        return sum / static_cast<double>(values.size());
    };
    std::vector<float> blind, blind_sigma;
    const auto blind_choice = wall.choose(true, &blind, "rebuild,input,spatial", &blind_sigma);
    CHECK(std::count(blind_choice.begin(), blind_choice.end(), 0) == std::ptrdiff_t(blind_choice.size()));
    CHECK(blind == wall.input);
    const double input_error = mean_square(wall.input);

    wall.repeating_share = 1;
    std::vector<float> counted, counted_sigma;
    const auto choice = wall.choose(true, &counted, "rebuild,input,spatial", &counted_sigma);
    const auto rebuilt = std::count(choice.begin(), choice.end(), 0);
    MESSAGE("rebuild kept at " << rebuilt << " of " << choice.size() << " pixels");
    CHECK(rebuilt < std::ptrdiff_t(choice.size() / 10));
    const double error = mean_square(counted);
    MESSAGE("mean square error: input " << input_error << ", counted " << error);
    CHECK(error < 0.2 * input_error);
    double sigma_square = 0;
    for (float value : counted_sigma)
        sigma_square += double(value) * value;
    sigma_square /= static_cast<double>(counted_sigma.size());
    MESSAGE("RMS sigma / RMS error " << std::sqrt(sigma_square / error));
    CHECK(sigma_square > 0.5 * 0.5 * error);
    CHECK(sigma_square < 2.0 * 2.0 * error);
    // Blind, sigma was the rebuild's 0.2 of the noise: 5x too small.
    CHECK(blind_sigma.front() == doctest::Approx(0.01));
}

TEST_CASE("estimators: on pure noise around an unbiased rebuild the one-sided test never fires")
{
    for (unsigned seed = 1; seed <= 4; ++seed) {
        CAPTURE(seed);
        WallFrame wall(0.05f, seed);
        CHECK(wall.choose(true) == wall.choose(false));
    }
}

TEST_CASE("estimators: in a frame far cleaner than the shot, the one-sided test uses the frame's noise")
{
    // The frame's noise is 0.02, the shot's pooled noise 0.2 (its other frames
    // lit by a noisier light). A 1 × 3 sliver of shadow 0.4 below the rebuild:
    // too shallow for noise of 0.2, far too deep for noise of 0.02.
    WallFrame wall(0.02f, 5, 0.2f);
    const int sliver_x = 30;
    for (int y = 10; y < 13; ++y)
        for (int c = 0; c < 3; ++c)
            wall.input[wall.at(sliver_x, y, c)] = 0.1f;
    auto taken = [&](const std::vector<std::uint8_t>& chosen, int y) {
        return static_cast<Estimator>(chosen[static_cast<size_t>(y) * wall.width + sliver_x]);
    };
    const std::vector<std::uint8_t> shot_scale = wall.choose(true);
    wall.noise_factor = 0.1; // the frame's level over the shot's
    std::vector<float> values;
    const std::vector<std::uint8_t> frame_scale = wall.choose(true, &values);
    for (int y = 10; y < 13; ++y) {
        CAPTURE(y);
        CHECK(taken(shot_scale, y) == Estimator::Rebuild);
        CHECK(taken(frame_scale, y) != Estimator::Rebuild);
        CHECK(values[wall.at(sliver_x, y)] < 0.3f);
    }
    // Where the frame is only noise around the rebuild, the frame's scale fires nowhere.
    for (unsigned seed = 1; seed <= 4; ++seed) {
        CAPTURE(seed);
        WallFrame clean(0.02f, seed, 0.2f);
        clean.noise_factor = 0.1;
        CHECK(clean.choose(true) == clean.choose(false));
    }
}

TEST_CASE(
    "estimators: a pixel steady in time and far from the rebuild takes the input, above or below it, and a "
    "lone firefly does not")
{
    WallFrame wall(0.02f, 17);
    // The frames around: the wall's noise afresh in each, but two pixels the
    // rebuild misses read the same in every frame, as a lit or shadowed edge
    // does while the rebuild shows other frames' light: 0.5 above it (about 19
    // steady spreads are needed above, 22 less the trend, the row neighbours'
    // noise making the spread about (0.016)²) and 0.3 below (14 spreads).
    const int above_x = 20, below_x = 40, row = 20, firefly_x = 44, firefly_y = 30;
    std::mt19937 generator(5);
    std::normal_distribution<float> normal(0.0f, 0.02f);
    std::vector<std::vector<float>> around(2 * kSpreadFrames, std::vector<float>(wall.input.size()));
    for (auto& frame : around)
        for (float& value : frame)
            value = 0.5f + normal(generator);
    for (int c = 0; c < 3; ++c) {
        wall.input[wall.at(above_x, row, c)] = 1.0f, wall.input[wall.at(below_x, row, c)] = 0.2f;
        for (auto& frame : around)
            frame[wall.at(above_x, row, c)] = 1.0f, frame[wall.at(below_x, row, c)] = 0.2f;
        wall.input[wall.at(firefly_x, firefly_y, c)] = 6.0f; // in this frame only
    }
    SpreadWindow window;
    window.image = {wall.width, wall.height, wall.channels};
    for (int k = 0, j = 0; k < 2 * kSpreadFrames + 1; ++k)
        window.frames[static_cast<size_t>(k)] = k == kSpreadFrames ? wall.input.data() : around[j++].data();
    const std::vector<std::uint8_t> without = wall.choose(false);
    wall.spread.resize(static_cast<size_t>(wall.width) * wall.height * kSpreadEstimates);
    wall.spread_terms.resize(wall.spread.size());
    spread_rows(window, 0, wall.height, wall.spread.data(), wall.spread_terms.data());
    std::vector<float> values;
    const std::vector<std::uint8_t> with = wall.choose(false, &values);
    int changed = 0;
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x) {
            const size_t pixel = static_cast<size_t>(y) * wall.width + x;
            if (with[pixel] != without[pixel]) {
                ++changed;
                CAPTURE(x);
                CAPTURE(y);
                CHECK(y == row);
                CHECK((x == above_x || x == below_x));
                CHECK(static_cast<Estimator>(with[pixel]) == Estimator::Input);
            }
        }
    CHECK(changed == 2);
    CHECK(values[wall.at(above_x, row)] == 1.0f);
    CHECK(values[wall.at(below_x, row)] == 0.2f);
    CHECK(static_cast<Estimator>(with[static_cast<size_t>(firefly_y) * wall.width + firefly_x]) ==
          Estimator::Rebuild);
    // Without the input as a candidate there is nothing the test could take.
    const std::vector<std::uint8_t> no_input = wall.choose(false, nullptr, "rebuild,spatial");
    CHECK(static_cast<Estimator>(no_input[static_cast<size_t>(row) * wall.width + above_x]) !=
          Estimator::Input);
}

TEST_CASE(
    "estimators: a blur that carries a bright patch's light onto a steady dim wall gives way to the input")
{
    // A dim wall (0.16, noise 0.002: steady in time) beside a bright patch
    // (20), as a lit region next to a dim one. The rebuild smears the patch
    // (a 2-pixel box of it, as a mode filter at a hard edge does), so its
    // residual, and the noise level taken from it, is large around the patch,
    // and a blur wins the window test there while carrying the patch's light
    // onto the dim pixels next to it.
    const float dim = 0.16f, bright = 20.0f, noise = 0.002f;
    WallFrame wall(noise, 23);
    const int x0 = 28, x1 = 36, y0 = 18, y1 = 26;
    auto in_patch = [&](int x, int y) { return x >= x0 && x < x1 && y >= y0 && y < y1; };
    std::vector<float> truth(wall.input.size());
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float value = in_patch(x, y) ? bright : dim;
                truth[wall.at(x, y, c)] = value;
                wall.input[wall.at(x, y, c)] += value - 0.5f;
            }
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x) {
            double sum = 0;
            int count = 0;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    if (x + dx >= 0 && x + dx < wall.width && y + dy >= 0 && y + dy < wall.height)
                        sum += truth[wall.at(x + dx, y + dy)], ++count;
            for (int c = 0; c < 3; ++c)
                wall.rebuilt[wall.at(x, y, c)] = static_cast<float>(sum / count);
        }
    // The frames around: the same scene, the noise afresh.
    std::mt19937 generator(29);
    std::normal_distribution<float> normal(0.0f, noise);
    std::vector<std::vector<float>> around(2 * kSpreadFrames, truth);
    for (auto& frame : around)
        for (float& value : frame)
            value += normal(generator);
    SpreadWindow window;
    window.image = {wall.width, wall.height, wall.channels};
    for (int k = 0, j = 0; k < 2 * kSpreadFrames + 1; ++k)
        window.frames[static_cast<size_t>(k)] = k == kSpreadFrames ? wall.input.data() : around[j++].data();
    std::vector<float> before, after;
    const std::vector<std::uint8_t> without = wall.choose(true, &before);
    wall.spread.resize(static_cast<size_t>(wall.width) * wall.height * kSpreadEstimates);
    wall.spread_terms.resize(wall.spread.size());
    spread_rows(window, 0, wall.height, wall.spread.data(), wall.spread_terms.data());
    const std::vector<std::uint8_t> with = wall.choose(true, &after);
    // Before: blurs taken on the dim wall, some of them far off (> 50 noise
    // standard deviations); after: every dim pixel within the test's reach of
    // the truth (above the input it is about 19 spreads of about one noise
    // deviation each, so that a lone firefly does not pass).
    int blurred_far = 0;
    double worst_after = 0;
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x) {
            if (in_patch(x, y))
                continue;
            const size_t pixel = static_cast<size_t>(y) * wall.width + x;
            const auto was = static_cast<Estimator>(without[pixel]);
            if ((was == Estimator::Gauss1 || was == Estimator::Gauss2) &&
                std::abs(before[wall.at(x, y)] - dim) > 50 * noise)
                ++blurred_far;
            worst_after = std::max(worst_after, static_cast<double>(std::abs(after[wall.at(x, y)] - dim)));
            if (with[pixel] != without[pixel]) {
                CAPTURE(x);
                CAPTURE(y);
                CHECK(static_cast<Estimator>(with[pixel]) == Estimator::Input);
            }
        }
    MESSAGE("dim pixels a blur took far off before: ", blurred_far, "; worst after: ", worst_after);
    CHECK(blurred_far > 0);
    CHECK(worst_after < 20 * noise);
}

TEST_CASE(
    "estimators: a rebuild whose misfit is busy in space does not hide behind the noise level it raises")
{
    // The rebuild misses the wall by ±0.1 in alternate columns (5 noise standard
    // deviations): its residual's high-pass is mostly that misfit, which would
    // make the noise level v, taken from it, about 20× the input's noise
    // variance, and with it the sigma of the blurs and the input taken instead.
    // v is bounded by the input's own high-pass power.
    const float noise = 0.02f;
    WallFrame wall(noise, 31);
    for (int y = 0; y < wall.height; ++y)
        for (int x = 0; x < wall.width; ++x)
            for (int c = 0; c < 3; ++c)
                wall.rebuilt[wall.at(x, y, c)] = 0.5f + (x % 2 ? 0.1f : -0.1f);
    std::vector<float> values, sigma;
    const std::vector<std::uint8_t> chosen = wall.choose(true, &values, "rebuild,input,spatial", &sigma);
    double input_error = 0, output_error = 0, sigma_squared = 0;
    int rebuilt = 0;
    for (size_t i = 0; i < values.size(); ++i) {
        input_error += (wall.input[i] - 0.5) * (wall.input[i] - 0.5);
        output_error += (values[i] - 0.5) * (values[i] - 0.5);
        sigma_squared += double(sigma[i]) * sigma[i];
    }
    for (std::uint8_t k : chosen)
        rebuilt += static_cast<Estimator>(k) == Estimator::Rebuild;
    const double calibration = std::sqrt(sigma_squared / output_error);
    MESSAGE("rebuild kept at " << rebuilt << " of " << chosen.size() << " pixels; MSE output / input "
                               << output_error / input_error << "; RMS(sigma) / RMS(error) " << calibration);
    CHECK(rebuilt < static_cast<int>(chosen.size()) / 20);
    CHECK(output_error < input_error);
    // Sigma: the chosen blurs' own error, not the misfit's (it was 4× too wide).
    CHECK(calibration > 0.67);
    CHECK(calibration < 1.5);
}

TEST_CASE("estimators: a blur's sigma counts the bias its risk shows, though no single window proves it")
{
    // Stripes of period 10 px that the rebuild misses (it is the flat 0.5), under
    // noise of 0.1: the 1 px Gaussian wins there and keeps a bias of about a fifth
    // of the stripes' amplitude at their crests, of the order of the pooled SURE's
    // own noise, so no window shows it at 2 standard errors. Sigma of the blurred
    // values must still describe their error (before, it was the blur's variance
    // part alone on most of them: RMS(error) / RMS(sigma) 1.45–1.59).
    for (unsigned seed = 1; seed <= 3; ++seed) {
        CAPTURE(seed);
        WallFrame wall(0.1f, seed);
        std::vector<float> truth(wall.input.size(), 0.5f);
        for (int y = 0; y < wall.height; ++y)
            for (int x = 0; x < wall.width; ++x)
                for (int c = 0; c < wall.channels; ++c) {
                    const float stripe = 0.3f * static_cast<float>(std::sin(2 * 3.14159265358979 * x / 10));
                    truth[wall.at(x, y, c)] += stripe, wall.input[wall.at(x, y, c)] += stripe;
                }
        std::vector<float> values, sigma;
        const std::vector<std::uint8_t> chosen = wall.choose(true, &values, "rebuild,input,spatial", &sigma);
        double error = 0, sigma_square = 0;
        int blurred = 0;
        for (int y = 4; y < wall.height - 4; ++y) // off the image's edges, where a blur's weights are clipped
            for (int x = 4; x < wall.width - 4; ++x) {
                const auto taken = static_cast<Estimator>(chosen[static_cast<size_t>(y) * wall.width + x]);
                if (taken != Estimator::Gauss1 && taken != Estimator::Gauss2)
                    continue;
                ++blurred;
                for (int c = 0; c < wall.channels; ++c) {
                    const size_t i = wall.at(x, y, c);
                    error += (double(values[i]) - truth[i]) * (double(values[i]) - truth[i]);
                    sigma_square += double(sigma[i]) * sigma[i];
                }
            }
        REQUIRE(blurred > (wall.width - 8) * (wall.height - 8) / 2);
        const double ratio = std::sqrt(error / sigma_square);
        MESSAGE("blurred pixels " << blurred << ", RMS(error) / RMS(sigma) " << ratio);
        CHECK(ratio > 0.7);
        CHECK(ratio < 1.25);
    }
}

TEST_CASE("estimators: a lasting misfit of single pixels takes the input where the rebuild's sigma admits "
          "it is no better, and only there")
{
    WallFrame wall(0.02f, 21);
    // Three single pixels the rebuild misses by 3 noise widths in this frame
    // and, by their statistics in time, in the frames around (temporal_misfit.h):
    // mean residual −0.06, scatter 0.02², 5 frames, 12 degrees of freedom before.
    wall.misfit.assign(static_cast<size_t>(wall.width) * wall.height * kMisfitValues, 0.0f);
    const int xs[] = {10, 30, 50};
    for (int x : xs) {
        for (int c = 0; c < wall.channels; ++c)
            wall.rebuilt[wall.at(x, 20, c)] += 0.06f;
        float* values = wall.misfit.data() + (static_cast<size_t>(20) * wall.width + x) * kMisfitValues;
        values[0] = -0.06f, values[1] = 0.02f * 0.02f, values[2] = 5, values[3] = 12;
    }
    auto taken = [&](const std::vector<std::uint8_t>& chosen, int x) {
        return static_cast<Estimator>(chosen[static_cast<size_t>(20) * wall.width + x]);
    };
    // The rebuild's sigma (0.2 × the noise) says it is far better than the
    // input: the test is not asked.
    const std::vector<std::uint8_t> sure = wall.choose(true);
    for (int x : xs)
        CHECK(taken(sure, x) == Estimator::Rebuild);
    // Its sigma a little wider than the input's scatter there: the input.
    for (int x : xs)
        for (int c = 0; c < wall.channels; ++c)
            wall.sigma[wall.at(x, 20, c)] = 0.021f;
    const std::vector<std::uint8_t> unsure = wall.choose(true);
    for (int x : xs)
        CHECK(taken(unsure, x) == Estimator::Input);
    // Without the input among the estimators there is no such test.
    const std::vector<std::uint8_t> no_input = wall.choose(true, nullptr, "rebuild,spatial");
    for (int x : xs)
        CHECK(taken(no_input, x) != Estimator::Input);
    // Elsewhere the rebuild stays where it was taken.
    std::vector<float> plain_misfit;
    wall.misfit.swap(plain_misfit);
    const std::vector<std::uint8_t> without = wall.choose(true);
    wall.misfit.swap(plain_misfit);
    for (size_t i = 0; i < unsure.size(); ++i)
        if (i != static_cast<size_t>(20) * wall.width + 10 &&
            i != static_cast<size_t>(20) * wall.width + 30 && i != static_cast<size_t>(20) * wall.width + 50)
            CHECK(unsure[i] == without[i]);
}

TEST_CASE("estimators: of two blurs that both beat the rebuild, the one with the larger gain over the window "
          "is taken, not a chance pick of nine pixels")
{
    // A flat wall whose noise the rebuild keeps whole (noise that repeats): both
    // blurs pass everywhere, and the wider one is better everywhere. The least
    // SURE over 3×3 pixels, a difference of noisy numbers, took the narrower
    // one at a share of the pixels by chance.
    WallFrame wall(0.05f, 11);
    wall.rebuilt = wall.input;
    wall.repeating_share = 1;
    std::vector<float> values;
    const auto choice = wall.choose(true, &values, "rebuild,input,spatial");
    const auto narrow = std::count(choice.begin(), choice.end(), static_cast<std::uint8_t>(Estimator::Gauss1)),
               wide = std::count(choice.begin(), choice.end(), static_cast<std::uint8_t>(Estimator::Gauss2));
    MESSAGE("1 px blur at " << narrow << ", 2 px blur at " << wide << " of " << choice.size() << " pixels");
    CHECK(wide > std::ptrdiff_t(choice.size() * 95 / 100));
}

TEST_CASE("estimators: where noise repeats, a rebuild no better than the input must show it, or the input is "
          "taken")
{
    // The input is a + e: a repeats from frame to frame (the rebuild keeps it
    // whole), e is new in each frame (the rebuild removes it). The rebuild is
    // a + a bias slightly larger than e: worse than the input by 0.21·var(e)
    // per sample, too little for the window test to reject. Both risks miss
    // a's part alike, so the test is fair; only its null decides.
    WallFrame wall(0.05f, 13);
    std::mt19937 generator(17);
    std::normal_distribution<float> repeating(0.0f, 0.04f), fresh(0.0f, 0.03f);
    const float bias = 1.1f * 0.03f;
    for (size_t i = 0; i < wall.input.size(); ++i) {
        const float a = repeating(generator);
        wall.input[i] = 0.5f + a + fresh(generator);
        wall.rebuilt[i] = 0.5f + a + bias;
    }
    auto mean_square = [&](const std::vector<float>& values) {
        double sum = 0;
        for (float value : values)
            sum += (value - 0.5) * (value - 0.5);
        return sum / static_cast<double>(values.size());
    };
    const double input_error = mean_square(wall.input), rebuilt_error = mean_square(wall.rebuilt);
    std::vector<float> unaware, aware;
    wall.choose(true, &unaware, "rebuild,input");
    wall.noise_repeats = true;
    const auto choice = wall.choose(true, &aware, "rebuild,input");
    const auto inputs = std::count(choice.begin(), choice.end(), static_cast<std::uint8_t>(Estimator::Input));
    MESSAGE("mean square error: input " << input_error << ", rebuild " << rebuilt_error << ", chosen "
                                        << mean_square(unaware) << " (noise not known to repeat), "
                                        << mean_square(aware) << " (known); input at " << inputs << " of "
                                        << choice.size() << " pixels");
    CHECK(rebuilt_error > input_error);
    CHECK(mean_square(unaware) > input_error); // the rebuild kept where it could not be rejected
    CHECK(mean_square(aware) < 1.01 * input_error);
    CHECK(inputs > std::ptrdiff_t(choice.size() * 9 / 10));
}

TEST_CASE("estimators: noise that repeats where the risks do not count it is still in sigma")
{
    // The rebuild keeps the frame's noise whole, and the noise is found to
    // repeat but not counted (on direct light its high-pass is mostly edges):
    // whatever is taken carries that noise, and sigma must say so.
    WallFrame wall(0.05f, 19);
    wall.rebuilt = wall.input;
    wall.noise_repeats = true;
    std::vector<float> values, blind_sigma, sigma;
    wall.choose(true, &values, "rebuild,input,spatial", &blind_sigma);
    wall.uncounted_share = 1;
    wall.choose(true, &values, "rebuild,input,spatial", &sigma);
    double error = 0, blind = 0, counted = 0;
    for (size_t i = 0; i < values.size(); ++i) {
        error += (values[i] - 0.5) * (values[i] - 0.5);
        blind += double(blind_sigma[i]) * blind_sigma[i], counted += double(sigma[i]) * sigma[i];
    }
    MESSAGE("RMS(error) / RMS(sigma): " << std::sqrt(error / blind) << " without the share, "
                                        << std::sqrt(error / counted) << " with it");
    CHECK(std::sqrt(error / blind) > 3); // the rebuild's own sigma: far too small
    CHECK(std::sqrt(error / counted) > 0.7);
    CHECK(std::sqrt(error / counted) < 1.4);
}
