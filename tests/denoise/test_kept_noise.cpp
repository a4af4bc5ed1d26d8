// Sigma's kept noise counts what each mode holds of the noise (band_rebuild.h,
// KeptNoise). The SVD fits its noise modes to the noisiest frames: in a shot
// whose last frames are noisier than the rest (a light switched on), those
// modes hold several times the pooled noise and carry it, through their
// weights, into the quieter frames, where sigma must see it. With the frames'
// measured noise (frame_weighting.h, the default) the modes are fitted to
// noise made even, and the quieter frames keep far less of the noisier ones'.
#include "core/denoise/band_rebuild.h"
#include "core/denoise/engine.h"
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

struct Calibration {
    double ratio = 0;         // RMS(error) / RMS(sigma) over the quieter frames
    double noisier_ratio = 0; // the same over the noisier frames
    double quiet_error = 0;   // MSE of the quieter frames
    double largest_scale = 0; // of the kept modes' noise scales
    int kept_modes = 0;
};

// A rank-2 shot (a smooth picture whose light fades, and a second light that
// comes and goes) of 32 frames under Gaussian noise: `quiet` in frames 0–23,
// 0.2 in frames 24–31. Default settings but for the firefly clamp, the frames'
// noise measured or taken as even.
Calibration quiet_frames_calibration(float quiet, bool measured_frame_noise = true)
{
    const int width = 64, height = 48, frames = 32, quiet_frames = 24;
    MemoryShot shot;
    shot.size = {frames, width, height, 3};
    std::mt19937 generator(21);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    auto truth = [&](int t, int x, int y) {
        const float fade = 1.0f - 0.02f * static_cast<float>(t);
        const float second = 0.3f + 0.2f * std::sin(0.3f * static_cast<float>(t));
        return fade * (0.5f + 0.3f * std::sin(0.1f * static_cast<float>(x))) +
               second * (0.4f + 0.2f * std::cos(0.13f * static_cast<float>(y)));
    };
    for (int t = 0; t < frames; ++t) {
        const float noise = t < quiet_frames ? quiet : 0.2f;
        std::vector<float> frame(static_cast<size_t>(width) * height * 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    frame[(static_cast<size_t>(y) * width + x) * 3 + c] =
                        truth(t, x, y) + noise * normal(generator);
        shot.frames.push_back(frame);
    }
    MemorySink sink(shot.size);
    Settings settings = gaussian_noise_settings();
    settings.measured_frame_noise = measured_frame_noise;
    const Report report = run_denoise(shot, sink, settings, Progress::silent());
    Calibration result;
    result.kept_modes = report.mode_filter.kept_modes;
    for (const ModeFilterChoice& mode : report.mode_filter.modes)
        if (mode.kept)
            result.largest_scale = std::max(result.largest_scale, mode.noise_scale);
    double error[2] = {}, sigma[2] = {};
    for (int t = 0; t < frames; ++t)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    const size_t i = (static_cast<size_t>(y) * width + x) * 3 + c;
                    const double e = sink.rebuilt[static_cast<size_t>(t)][i] - truth(t, x, y);
                    const double s = sink.sigma[static_cast<size_t>(t)][i];
                    const int part = t < quiet_frames ? 0 : 1;
                    error[part] += e * e, sigma[part] += s * s;
                }
    result.ratio = std::sqrt(error[0] / sigma[0]);
    result.noisier_ratio = std::sqrt(error[1] / sigma[1]);
    result.quiet_error = error[0] / (static_cast<double>(quiet_frames) * width * height * 3);
    return result;
}

} // namespace

TEST_CASE("kept noise: with the same noise in every frame, sigma is calibrated")
{
    const Calibration same = quiet_frames_calibration(0.2f);
    MESSAGE("kept modes " << same.kept_modes << ", largest noise scale " << same.largest_scale
                          << ", RMS(error) / "
                          << "RMS(sigma) " << same.ratio);
    CHECK(same.ratio > 0.8);
    CHECK(same.ratio < 1.25);
}

TEST_CASE("kept noise: sigma of the quieter frames counts the noise modes fitted to the noisier ones")
{
    // The last quarter 4× as noisy and taken as even: the survey keeps noise
    // modes (their noise scale at the cap, 4), and the quieter frames' error is
    // 2.3× their sigma when each mode counts only its share of the pooled noise.
    const Calibration mixed = quiet_frames_calibration(0.05f, false);
    MESSAGE("kept modes " << mixed.kept_modes << ", largest noise scale " << mixed.largest_scale
                          << ", quieter frames' RMS(error) / RMS(sigma) " << mixed.ratio);
    CHECK(mixed.largest_scale > 2);
    CHECK(mixed.ratio > 0.8);
    CHECK(mixed.ratio < 1.8);
}

TEST_CASE("kept noise: modes fitted to the frames' measured noise keep the noisier frames' noise out of the "
          "quieter ones, and sigma stays calibrated in both")
{
    const Calibration even = quiet_frames_calibration(0.05f, false);
    const Calibration measured = quiet_frames_calibration(0.05f, true);
    MESSAGE("quieter frames' MSE: even " << even.quiet_error << ", measured " << measured.quiet_error
                                         << "; RMS(error) / RMS(sigma) quieter " << measured.ratio
                                         << ", noisier " << measured.noisier_ratio << "; largest noise scale "
                                         << measured.largest_scale);
    CHECK(measured.quiet_error < 0.5 * even.quiet_error);
    CHECK(measured.largest_scale < 2); // no mode holds the noisier frames' noise alone
    for (double ratio : {measured.ratio, measured.noisier_ratio}) {
        CHECK(ratio > 0.8);
        CHECK(ratio < 1.25);
    }
}
