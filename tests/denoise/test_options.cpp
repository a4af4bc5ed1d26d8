// The method options of `denoise` (issue 8) on synthetic shots with a known
// truth: --transform round-trips to float precision and its bias has the sign
// the maths predicts; --non-negative leaves no value below 0 and counts what it
// changed; --shrink optimal has no more error than hard truncation; bad
// segments finds a planted lighting cut at its frame and parses lists; modes
// from every 4th frame rebuild all frames of a rank-3 shot exactly; bad
// combinations are usage errors.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/denoise/non_negative.h"
#include "core/denoise/segments.h"
#include "core/denoise/training.h"
#include "core/denoise/transform.h"
#include "core/lowrank/shrinkage.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;
using namespace modestack::denoise::testing;

namespace {

// Rank-3 positive light: ambient, a moving lobe with a hard edge, a flicker; plus
// Gaussian noise of standard deviation `noise` (relative to the value when `relative`).
MemoryShot light_shot(int width, int height, int frames, float noise, unsigned seed, bool relative = false)
{
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    for (int t = 0; t < frames; ++t) {
        const float time = static_cast<float>(t) / frames;
        std::vector<float> frame(std::size_t(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    const float ambient = 0.5f + 0.2f * std::sin(0.3f * x + c);
                    const float lobe = (x > width / 3 ? 1.0f : 0.05f) * (1.0f + std::cos(0.2f * y));
                    const float spot = ((x / 4 + y / 4) % 3 == 0) ? 0.8f : 0.0f;
                    const float value = ambient * (1.0f + 0.3f * time) + lobe * time * time +
                                        spot * (0.5f + 0.5f * std::sin(6.0f * time));
                    const float scale = relative ? value : 1.0f;
                    frame[(std::size_t(y) * width + x) * 3 + c] =
                        value + (noise > 0 ? noise * scale * normal(generator) : 0.0f);
                }
        shot.frames.push_back(frame);
    }
    return shot;
}

Settings plain(int kept_modes = 0)
{
    Settings settings;
    settings.outliers.fireflies = false;
    settings.mode_filter.enabled = false;
    if (kept_modes > 0) {
        settings.rank_rule.rule = lowrank::RankRule::Fixed;
        settings.rank_rule.fixed_modes = kept_modes;
    }
    return settings;
}

double mean_of(const std::vector<std::vector<float>>& frames)
{
    double sum = 0;
    std::size_t count = 0;
    for (const auto& frame : frames)
        for (float value : frame) {
            sum += value;
            ++count;
        }
    return sum / count;
}

} // namespace

TEST_CASE("transform: parsing, and every map round-trips to float precision")
{
    CHECK(parse_transform("none").kind == TransformKind::None);
    CHECK(parse_transform("log").epsilon_fraction == 0.1);
    CHECK(parse_transform("log:0.05").epsilon_fraction == 0.05);
    CHECK(parse_transform("pow:2.2").gamma == 2.2);
    CHECK(transform_name(parse_transform("pow:2.2")) == "pow:2.2");
    for (const char* bad : {"exp", "pow:", "pow:0.5", "pow:9", "log:-1", "log:x", "pow:2x"})
        CHECK_THROWS_WITH_AS(parse_transform(bad), doctest::Contains("--transform"), Error);

    std::mt19937 generator(7);
    std::uniform_real_distribution<float> uniform(0.0f, 50.0f);
    std::vector<float> values(10000);
    for (float& value : values)
        value = uniform(generator) * uniform(generator) / 50.0f; // many values near 0
    values[0] = 0.0f;
    for (std::string text : {"log", "pow:2", "pow:2.2", "pow:8"}) {
        CAPTURE(text);
        Transform transform = parse_transform(text);
        transform.epsilon = 0.02;
        std::vector<float> mapped = values;
        apply_forward(transform, mapped.data(), mapped.size());
        if (transform.kind == TransformKind::Power) // sign-preserving: negatives round-trip too
            for (std::size_t i = 0; i < mapped.size(); i += 2)
                mapped[i] = -mapped[i];
        std::vector<float> back = mapped;
        apply_inverse(transform, back.data(), back.size());
        double worst = 0;
        for (std::size_t i = 0; i < values.size(); ++i) {
            const float expected =
                transform.kind == TransformKind::Power && i % 2 == 0 ? -values[i] : values[i];
            worst = std::max(worst, std::fabs(back[i] - expected) / (std::fabs(expected) + 0.02));
        }
        MESSAGE(text << ": largest round-trip error " << worst << " (relative to |x| + 0.02)");
        CHECK(worst < 2e-6);
        // Sigma: the delta method's slope is the inverse's derivative (central differences).
        for (float y : {-1.5f, -0.2f, 0.3f, 1.0f, 2.5f}) {
            if (transform.kind == TransformKind::Log && y < 0)
                y = -y;
            float sigma = 1.0f, low = y - 1e-3f, high = y + 1e-3f;
            map_sigma_back(transform, &y, &sigma, 1);
            apply_inverse(transform, &low, 1);
            apply_inverse(transform, &high, 1);
            CHECK(sigma == doctest::Approx((high - low) / 2e-3).epsilon(1e-3));
        }
    }
    Transform log = parse_transform("log");
    log.epsilon = 0.5;
    CHECK(transformed_zero(log) == doctest::Approx(std::log(0.5)));
    CHECK(transformed_zero(parse_transform("pow:3")) == 0.0f);
}

TEST_CASE("transform: through the engine a static shot comes back exactly, and on noise log is biased low")
{
    // A static shot is rank 1 in any per-value map: the decorators must give it back.
    MemoryShot still = light_shot(20, 12, 8, 0.0f, 1);
    for (int t = 1; t < 8; ++t)
        still.frames[t] = still.frames[0];
    for (std::string text : {"log", "pow:2"}) {
        CAPTURE(text);
        Transform transform = parse_transform(text);
        transform.epsilon = transform.epsilon_fraction * sample_shot_mean(still);
        TransformSource source(still, transform);
        MemorySink sink(still.size);
        InverseTransformSink inverse(sink, transform, still.size);
        run_denoise(source, inverse, plain(1), Progress::silent());
        CHECK(mean_square(sink.rebuilt, still.frames) < 1e-10);
    }

    // Noise of 40 % of the value (a few spp): the mean of the inverse is not the
    // inverse of the mean. Log loses light (Jensen), sqrt less, none nothing.
    MemoryShot clean = light_shot(40, 30, 24, 0.0f, 1);
    MemoryShot noisy = light_shot(40, 30, 24, 0.4f, 2, true);
    const double truth = mean_of(clean.frames);
    auto bias_and_error = [&](const std::string& text) {
        Transform transform = parse_transform(text);
        transform.epsilon = transform.epsilon_fraction * sample_shot_mean(noisy);
        TransformSource source(noisy, transform);
        MemorySink sink(noisy.size);
        InverseTransformSink inverse(sink, transform, noisy.size);
        run_denoise(source, inverse, plain(3), Progress::silent());
        return std::make_pair(mean_of(sink.rebuilt) / truth - 1, mean_square(sink.rebuilt, clean.frames));
    };
    auto [none_bias, none_error] = bias_and_error("none");
    auto [sqrt_bias, sqrt_error] = bias_and_error("pow:2");
    auto [log_bias, log_error] = bias_and_error("log");
    MESSAGE("mean bias: none " << none_bias << ", pow:2 " << sqrt_bias << ", log " << log_bias);
    MESSAGE("MSE: none " << none_error << ", pow:2 " << sqrt_error << ", log " << log_error);
    CHECK(std::fabs(none_bias) < 0.002);
    CHECK(log_bias < -0.02);
    CHECK(sqrt_bias < 0);
    CHECK(sqrt_bias > log_bias);
}

TEST_CASE("non-negative: no value below the floor, counts, and keep-sum keeps each sample's sum")
{
    // 5 samples over 4 frames.
    std::vector<float> band{
        1.0f, -1.0f, 0.5f,  2.0f,  -3.0f, // frame 0
        2.0f, 1.0f,  -0.5f, 2.0f,  -1.0f, // frame 1
        3.0f, 1.0f,  0.5f,  -1.0f, 1.0f,  // frame 2
        4.0f, 2.0f,  0.5f,  2.0f,  1.0f,  // frame 3
    };
    for (NonNegativeMode mode : {NonNegativeMode::Clamp, NonNegativeMode::KeepSum}) {
        CAPTURE(non_negative_mode_name(mode));
        std::vector<float> fixed = band;
        NonNegativeCounts counts = make_non_negative({fixed.data(), 5, 4, 5}, mode, 0.0f);
        for (float value : fixed)
            CHECK(value >= 0.0f);
        CHECK(counts.clamped == 5);
        CHECK(counts.samples == 4);
        CHECK(fixed[0] == 1.0f); // sample 0 had no negative value: untouched
        auto sum = [](const std::vector<float>& values, int sample) {
            double total = 0;
            for (int t = 0; t < 4; ++t)
                total += values[t * 5 + sample];
            return total;
        };
        if (mode == NonNegativeMode::Clamp) {
            CHECK(counts.scaled == 0);
            CHECK(fixed[1] == 0.0f);
            CHECK(fixed[11] == 1.0f);
        } else {
            CHECK(counts.scaled == 3 + 3 + 3 + 2);
            for (int sample : {1, 2, 3}) // positive frames hold enough: the sum is kept
                CHECK(sum(fixed, sample) == doctest::Approx(sum(band, sample)));
            CHECK(sum(fixed, 4) == 0.0); // deficit 4 > positive 2: all black
        }
    }
    CHECK_THROWS_WITH_AS(parse_non_negative_mode("zero"), doctest::Contains("--non-negative-mode"), Error);

    // A rank-2 rebuild of a shot with a nearly black, noisy part dips below 0 there.
    MemoryShot shot = light_shot(30, 20, 12, 0.3f, 4);
    std::mt19937 generator(9);
    std::normal_distribution<float> normal(0.0f, 0.3f);
    for (auto& frame : shot.frames)
        for (std::size_t i = 0; i < frame.size(); i += 3 * 30)
            for (std::size_t k = i; k < i + 3 * 10; ++k) // the first 10 pixels of each row
                frame[k] = 0.02f + normal(generator);
    MemorySink off(shot.size), clamp(shot.size), keep(shot.size);
    Settings settings = plain(2);
    run_denoise(shot, off, settings, Progress::silent());
    std::int64_t negatives = 0;
    for (const auto& frame : off.rebuilt)
        negatives += std::count_if(frame.begin(), frame.end(), [](float v) { return v < 0; });
    REQUIRE(negatives > 0);
    settings.non_negative = NonNegativeMode::Clamp;
    Report report = run_denoise(shot, clamp, settings, Progress::silent());
    CHECK(report.non_negative.clamped == negatives);
    settings.non_negative = NonNegativeMode::KeepSum;
    Report keep_report = run_denoise(shot, keep, settings, Progress::silent());
    CHECK(keep_report.non_negative.clamped == negatives);
    CHECK(keep_report.non_negative.scaled > 0);
    for (const auto* sink : {&clamp, &keep})
        for (const auto& frame : sink->rebuilt)
            CHECK(*std::min_element(frame.begin(), frame.end()) >= 0.0f);
    MESSAGE(negatives << " negative values of " << shot.frames.size() * shot.frames[0].size()
                      << "; mean light " << mean_of(off.rebuilt) << " off, " << mean_of(clamp.rebuilt)
                      << " clamp, " << mean_of(keep.rebuilt) << " keep-sum");
    // Clamping adds light; keep-sum adds only where a pixel's frames sum below 0.
    CHECK(mean_of(clamp.rebuilt) > mean_of(keep.rebuilt));
    CHECK(mean_of(keep.rebuilt) >= mean_of(off.rebuilt));
}

TEST_CASE("shrink: the Gavish-Donoho shrinker, and optimal shrinkage has no more error than hard truncation")
{
    CHECK(lowrank::optimal_shrink_frobenius(1.9, 1.0) == 0.0); // inside the bulk (edge 1 + sqrt(1) = 2)
    CHECK(lowrank::optimal_shrink_frobenius(2.1, 1.0) > 0.0);
    CHECK(lowrank::optimal_shrink_frobenius(1000.0, 0.3) == doctest::Approx(1000.0).epsilon(1e-5));
    for (double y : {2.5, 4.0, 10.0}) // η(y) < y: a shrinker
        CHECK(lowrank::optimal_shrink_frobenius(y, 0.5) < y);

    MemoryShot clean = light_shot(48, 40, 24, 0.0f, 1);
    MemoryShot noisy = light_shot(48, 40, 24, 0.3f, 5);
    for (int kept_modes : {3, 6}) {
        CAPTURE(kept_modes);
        MemorySink hard(noisy.size), optimal(noisy.size);
        Settings settings = plain(kept_modes);
        // The shrinker's cut of the noise modes needs noise even over the frames:
        // the measured frame scales of this shot follow its spots' brightness as
        // well as its noise (frame_noise.h), ±15 %.
        settings.measured_frame_noise = false;
        run_denoise(noisy, hard, settings, Progress::silent());
        settings.optimal_shrinkage = true;
        Report report = run_denoise(noisy, optimal, settings, Progress::silent());
        const double hard_error = mean_square(hard.rebuilt, clean.frames);
        const double optimal_error = mean_square(optimal.rebuilt, clean.frames);
        MESSAGE("rank " << kept_modes << ": MSE hard " << hard_error << ", optimal " << optimal_error
                        << ", noise sigma " << report.rank_decision.noise_sigma << " (true 0.3)");
        CHECK(report.rank_decision.noise_sigma == doctest::Approx(0.3).epsilon(0.1));
        REQUIRE(report.shrinkage.size() == static_cast<size_t>(kept_modes));
        CHECK(report.shrinkage[0] > 0.95);
        for (int j = 3; j < kept_modes; ++j) // pure-noise modes are dropped
            CHECK(report.shrinkage[j] == 0.0);
        CHECK(optimal_error <= hard_error);
    }
    Settings both = plain(3);
    both.optimal_shrinkage = true;
    both.mode_filter.enabled = true;
    MemorySink sink(noisy.size);
    CHECK_THROWS_WITH_AS(run_denoise(noisy, sink, both, Progress::silent()),
                         doctest::Contains("--shrink optimal"), Error);
}

TEST_CASE("segments: lists cover the shot in order, and auto finds a planted lighting cut at its frame")
{
    std::vector<int> numbers{101, 102, 103, 104, 105, 106, 107, 108, 109, 110};
    std::vector<FrameSegment> parts = parse_segments("101-104,105-110", numbers);
    REQUIRE(parts.size() == 2);
    CHECK((parts[0].first == 0 && parts[0].count == 4 && parts[1].first == 4 && parts[1].count == 6));
    CHECK(parse_segments("101-110", numbers).size() == 1);
    for (const char* bad : {"101-104,106-110", "101-105,105-110", "101-102,103-110", "101-104,105-108", "a-b",
                            "101-104,105-120", "", "101-110,111-113"})
        CHECK_THROWS_WITH_AS(parse_segments(bad, numbers), doctest::Contains("--segments"), Error);

    // 24 frames; from frame index 13 on the lighting is another one (the scene
    // mirrored): each part has rank 3, the whole shot rank 6.
    const int cut = 13, width = 40, height = 32;
    MemoryShot clean = light_shot(width, height, 24, 0.0f, 1), noisy = light_shot(width, height, 24, 0.3f, 6);
    for (MemoryShot* shot : {&clean, &noisy})
        for (int t = cut; t < 24; ++t) {
            std::vector<float> mirrored = shot->frames[t];
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x)
                    for (int c = 0; c < 3; ++c)
                        mirrored[(std::size_t(y) * width + x) * 3 + c] =
                            shot->frames[t][(std::size_t(height - 1 - y) * width + (width - 1 - x)) * 3 + c];
            shot->frames[t] = mirrored;
        }
    CutSearch search = find_cuts(noisy);
    MESSAGE("distance at the cut " << search.distances[cut - 1] << ", median " << search.median
                                   << ", threshold " << search.threshold);
    CHECK(search.cuts == std::vector<int>{cut});
    MemoryShot smooth = light_shot(width, height, 24, 0.3f, 6);
    CHECK(find_cuts(smooth).cuts.empty()); // smooth lighting: no cut

    // Noise-free, N = 3: the parts are rebuilt exactly, the whole shot is not.
    std::vector<FrameSegment> halves = segments_from_cuts(search.cuts, 24);
    MemorySink whole(clean.size), split(clean.size);
    run_denoise(clean, whole, plain(3), Progress::silent());
    std::vector<Report> reports = run_segments(clean, split, plain(3), halves, Progress::silent());
    REQUIRE(reports.size() == 2);
    CHECK(reports[1].shape.frames == 24 - cut);
    Report merged = merge_reports(reports);
    CHECK(merged.shape.frames == 24);
    CHECK(merged.passes == reports[0].passes + reports[1].passes);
    const double whole_error = mean_square(whole.rebuilt, clean.frames);
    const double split_error = mean_square(split.rebuilt, clean.frames);
    MESSAGE("N = 3, noise-free: MSE whole shot " << whole_error << ", in two parts " << split_error);
    CHECK(split_error < 1e-10);
    CHECK(whole_error > 1e-3);
}

TEST_CASE("train frames: modes from every 4th frame rebuild every frame of a rank-3 shot exactly")
{
    MemoryShot clean = light_shot(36, 28, 24, 0.0f, 1);
    Settings settings = plain(3);
    settings.training_frames = {0, 4, 8, 12, 16, 20};
    MemorySink sink(clean.size);
    Report report = run_denoise(clean, sink, settings, Progress::silent());
    CHECK(report.singular_values.size() == 6); // the training frames' spectrum
    CHECK(report.singular_values[3] < 1e-5 * report.singular_values[0]);
    CHECK(mean_square(sink.rebuilt, clean.frames) < 1e-10);
    // The reported temporal modes cover every frame and lie in the span of the
    // full run's modes (of X itself: the training frames fit even noise too).
    MemorySink full_sink(clean.size);
    Settings even = plain(3);
    even.measured_frame_noise = false;
    Report full = run_denoise(clean, full_sink, even, Progress::silent());
    REQUIRE(report.temporal_modes.size() == 3);
    REQUIRE(report.temporal_modes[0].size() == 24);
    for (const std::vector<double>& mode : report.temporal_modes) {
        std::vector<double> residual = mode;
        for (const std::vector<double>& reference : full.temporal_modes) { // orthonormal
            double dot = 0;
            for (int t = 0; t < 24; ++t)
                dot += mode[t] * reference[t];
            for (int t = 0; t < 24; ++t)
                residual[t] -= dot * reference[t];
        }
        double left = 0, norm = 0;
        for (int t = 0; t < 24; ++t) {
            left += residual[t] * residual[t];
            norm += mode[t] * mode[t];
        }
        CHECK(std::sqrt(left / norm) < 1e-5);
    }

    // With noise: the training-frame basis is noisier, so the error grows a little.
    MemoryShot noisy = light_shot(36, 28, 24, 0.3f, 8);
    MemorySink trained(noisy.size), all(noisy.size);
    run_denoise(noisy, trained, settings, Progress::silent());
    run_denoise(noisy, all, plain(3), Progress::silent());
    const double trained_error = mean_square(trained.rebuilt, clean.frames),
                 all_error = mean_square(all.rebuilt, clean.frames);
    MESSAGE("N = 3, noise 0.3: MSE all frames " << all_error << ", modes from 6 of 24 frames "
                                                << trained_error);
    // The spatial modes carry the noise of the training frames only: the rebuild
    // keeps about N/F_T of the noise variance instead of N/F.
    CHECK(all_error == doctest::Approx(0.09 * 3 / 24).epsilon(0.3));
    CHECK(trained_error == doctest::Approx(0.09 * 3 / 6).epsilon(0.3));

    for (auto [training, message] :
         std::vector<std::pair<std::vector<int>, std::string>>{{{0, 4}, "at least 3"},
                                                               {{0, 4, 30}, "frames of the shot"},
                                                               {{4, 0, 8}, "ascending"},
                                                               {{0, 1, 2}, "--rank 3"}}) {
        Settings bad = plain(3);
        bad.training_frames = training;
        MemorySink unused(clean.size);
        CHECK_THROWS_WITH_AS(run_denoise(clean, unused, bad, Progress::silent()),
                             doctest::Contains(message.c_str()), Error);
    }
    Settings filtered = settings;
    filtered.mode_filter.enabled = true;
    MemorySink unused(clean.size);
    CHECK_THROWS_WITH_AS(run_denoise(clean, unused, filtered, Progress::silent()),
                         doctest::Contains("--no-mode-filter"), Error);
}
