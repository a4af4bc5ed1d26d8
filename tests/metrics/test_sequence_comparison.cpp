// core/metrics/sequence_comparison and verdict: flicker over time (zero for a
// constant offset, the closed form for alternating noise), shot totals pooled
// over frames, and idiff's pass/warn/fail rule at its boundaries.
#include "core/metrics/sequence_comparison.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace modestack::metrics;

namespace {
constexpr int kPixels = 12, kChannels = 3, kFrames = 6;

// A reference that changes over time; all values are exact in float.
std::vector<float> reference_frame(int frame)
{
    std::vector<float> values(kPixels * kChannels);
    for (int i = 0; i < kPixels * kChannels; ++i)
        values[i] = 0.25f * static_cast<float>(i % 5) + 0.125f * static_cast<float>(frame);
    return values;
}
} // namespace

TEST_CASE("flicker is exactly zero for a constant offset over time, though each frame has an error")
{
    SequenceComparison comparison(kPixels, kChannels, PixelThresholds{}, VerdictRule{});
    for (int frame = 0; frame < kFrames; ++frame) {
        std::vector<float> reference = reference_frame(frame), test = reference;
        for (float& v : test)
            v += 0.5f;
        FrameComparison result = comparison.add_frame(test.data(), reference.data());
        CHECK(result.sums.relative_mse() > 0.0);
        if (frame == 0)
            CHECK(std::isnan(result.sums.mean_flicker()));
        else
            CHECK(result.sums.mean_flicker() == 0.0);
    }
    CHECK(comparison.shot().mean_flicker() == 0.0);
    CHECK(comparison.shot().flicker_values == (kFrames - 1) * kPixels * kChannels);
    CHECK(comparison.frames() == kFrames);
}

TEST_CASE("alternating noise flickers: ((2a)^2) / (r^2 + 0.01) per value, with a static reference")
{
    const float amplitude = 0.0625f, reference_value = 0.75f;
    std::vector<float> reference(kPixels * kChannels, reference_value);
    SequenceComparison comparison(kPixels, kChannels, PixelThresholds{}, VerdictRule{});
    for (int frame = 0; frame < kFrames; ++frame) {
        std::vector<float> test = reference;
        for (float& v : test)
            v += frame % 2 ? amplitude : -amplitude;
        comparison.add_frame(test.data(), reference.data());
    }
    double expected = 4.0 * 0.0625 * 0.0625 / (0.75 * 0.75 + 0.01);
    CHECK(comparison.shot().mean_flicker() == doctest::Approx(expected).epsilon(1e-12));
    // Same per-frame error as a constant offset of the same size: only flicker tells them apart.
    CHECK(comparison.shot().relative_mse() ==
          doctest::Approx(0.0625 * 0.0625 / (0.75 * 0.75 + 0.01)).epsilon(1e-12));
}

TEST_CASE("shot totals pool every value of every frame, in frame order")
{
    SequenceComparison comparison(kPixels, kChannels, PixelThresholds{0.2, 0.1}, VerdictRule{});
    ErrorSums merged;
    double relative_sum = 0.0, max_error = 0.0;
    for (int frame = 0; frame < kFrames; ++frame) {
        std::vector<float> reference = reference_frame(frame), test = reference;
        test[frame] += 0.0625f * static_cast<float>(frame); // error grows with the frame
        FrameComparison result = comparison.add_frame(test.data(), reference.data());
        merged.merge(result.sums);
        relative_sum += result.sums.relative_mse();
        max_error = std::max(max_error, result.sums.max_absolute);
    }
    const ErrorSums& shot = comparison.shot();
    CHECK(shot.values == kFrames * kPixels * kChannels);
    CHECK(shot.relative_mse() == merged.relative_mse());
    // Equal-sized frames: the pooled relMSE is the mean of the per-frame relMSEs.
    CHECK(shot.relative_mse() == doctest::Approx(relative_sum / kFrames).epsilon(1e-12));
    CHECK(shot.max_absolute == max_error);
    CHECK(shot.max_absolute == 0.3125);
    // Frames 4 and 5 (errors 0.25, 0.3125) are over the fail threshold 0.2, frame 2 and 3 over warn only.
    CHECK(comparison.frames_failing() == 2);
    CHECK(comparison.frames_warning() == 2);
    CHECK(comparison.verdict() == Verdict::Failure);
}

TEST_CASE("verdict: idiff's rule at its boundaries")
{
    ErrorSums frame;
    frame.pixels = 200;
    frame.values = 600;
    frame.max_absolute = 0.5;
    frame.pixels_failing = 2; // 1 %
    frame.pixels_warning = 6; // 3 %

    VerdictRule rule;
    CHECK(judge(frame, rule) == Verdict::Failure); // default: no failing pixel allowed
    rule.fail_percent = 1.0;                       // exactly 1 % allowed: not more than it
    CHECK(judge(frame, rule) == Verdict::Warning); // 3 % warn > 0 %
    rule.warn_percent = 3.0;
    CHECK(judge(frame, rule) == Verdict::Pass);
    rule.hard_warn = 0.25;
    CHECK(judge(frame, rule) == Verdict::Warning);
    rule.hard_fail = 0.4999;
    CHECK(judge(frame, rule) == Verdict::Failure);
    rule.hard_fail = 0.5; // not over it
    CHECK(judge(frame, rule) == Verdict::Warning);
    rule.fail_percent = 0.99;
    CHECK(judge(frame, rule) == Verdict::Failure);

    VerdictRule generous;
    generous.fail_percent = generous.warn_percent = 100.0;
    CHECK(judge(frame, generous) == Verdict::Pass);
    frame.non_finite = 1; // a NaN/Inf mismatch fails whatever the percentages
    CHECK(judge(frame, generous) == Verdict::Failure);

    CHECK(worst(Verdict::Pass, Verdict::Warning) == Verdict::Warning);
    CHECK(worst(Verdict::Failure, Verdict::Warning) == Verdict::Failure);
    CHECK(std::string(verdict_name(Verdict::Pass)) == "PASS");
    CHECK(std::string(verdict_name(Verdict::Warning)) == "WARNING");
    CHECK(std::string(verdict_name(Verdict::Failure)) == "FAILURE");
}
