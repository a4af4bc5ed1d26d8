// The whole points × frames denoise on a synthetic shot: points on a floor and a
// wall (in a point image 64 wide, padded at the end as render --points pads it)
// whose light is exactly rank 2 over time. Without noise the rank-2 rebuild gives
// the points back, the surface filter leaves them alone and the leverages sum to
// N; with noise the surface filter lowers the error further than the temporal
// rebuild alone; without positions and normals it is the engine on the point
// image with everything spatial off, bit for bit; an input too large for the
// memory budget is read again per frame with the same bits.
#include "core/common/error.h"
#include "core/denoise/engine.h"
#include "core/objectspace/leverage.h"
#include "core/objectspace/point_denoise.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

using namespace modestack;
using denoise::testing::MemoryShot;
using denoise::testing::MemorySink;

namespace {

constexpr int kFrames = 24;
constexpr int kSide = 30;        // points per side of each face's lattice
constexpr int kImageWidth = 64;  // points per row of the point image
constexpr double kSpacing = 0.04;

struct PointShot {
    MemoryShot shot;      // what the engine reads (noisy)
    MemoryShot truth;     // the rank-2 light
    objectspace::SurfaceSamples samples;
};

PointShot make_point_shot(double noise)
{
    PointShot result;
    objectspace::SurfaceSamples& samples = result.samples;
    samples.spacing = kSpacing;
    for (int face = 0; face < 2; ++face)
        for (int i = 0; i < kSide; ++i)
            for (int j = 0; j < kSide; ++j) {
                const float a = static_cast<float>(i * kSpacing), b = static_cast<float>(j * kSpacing);
                if (face == 0) { // floor y = 0
                    samples.positions.insert(samples.positions.end(), {a, 0.0f, b});
                    samples.normals.insert(samples.normals.end(), {0.0f, 1.0f, 0.0f});
                } else { // wall x = 0
                    samples.positions.insert(samples.positions.end(), {0.0f, a + 0.01f, b});
                    samples.normals.insert(samples.normals.end(), {1.0f, 0.0f, 0.0f});
                }
            }
    const int count = static_cast<int>(samples.count());
    const int height = (count + kImageWidth - 1) / kImageWidth;
    result.truth.size = result.shot.size = {kFrames, kImageWidth, height, 3};
    std::mt19937 random(23);
    std::normal_distribution<double> gauss(0.0, noise);
    for (int t = 0; t < kFrames; ++t) {
        const double u = 1.0 + 0.3 * std::sin(0.4 * t), w = std::cos(0.25 * t);
        std::vector<float> truth(std::size_t(kImageWidth) * height * 3, 0.0f), noisy = truth;
        for (int p = 0; p < count; ++p)
            for (int c = 0; c < 3; ++c) {
                const float* at = &samples.positions[3 * p];
                const double first = 1.0 + 0.5 * at[0] + 0.2 * c, second = 0.4 * at[2] * (p < kSide * kSide ? 1 : -1);
                truth[p * 3 + c] = static_cast<float>(first * u + second * w);
                noisy[p * 3 + c] = static_cast<float>(truth[p * 3 + c] + (noise > 0 ? gauss(random) : 0.0));
            }
        result.truth.frames.push_back(truth);
        result.shot.frames.push_back(noisy);
    }
    return result;
}

objectspace::SurfaceFilterOptions filter_options()
{
    objectspace::SurfaceFilterOptions options;
    options.widths = {0.75, 1.0, 1.5, 2.0, 3.0};
    return options;
}

// Every frame's point values and sigma as the result makes them.
struct PointFrames {
    std::vector<std::vector<float>> values, sigma;
};

PointFrames frames_of(const objectspace::PointDenoise& result)
{
    PointFrames frames;
    for (int t = 0; t < kFrames; ++t) {
        frames.values.emplace_back(static_cast<std::size_t>(result.frame_values()));
        frames.sigma.emplace_back(frames.values.back().size());
        result.frame(t, frames.values.back().data(), frames.sigma.back().data());
    }
    return frames;
}

// RMS over the real points (not the padding) of every frame.
double rms_error(const PointShot& shot, const PointFrames& frames)
{
    const std::size_t values = static_cast<std::size_t>(shot.samples.count()) * 3;
    double sum = 0;
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t v = 0; v < values; ++v) {
            const double error = frames.values[t][v] - shot.truth.frames[t][v];
            sum += error * error;
        }
    return std::sqrt(sum / static_cast<double>(values * kFrames));
}

} // namespace

TEST_CASE("point denoise: rank-2 points are recovered, left unfiltered, and their leverages sum to N")
{
    PointShot shot = make_point_shot(0.0);
    denoise::Settings settings;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 2;
    objectspace::PointDenoise result =
        objectspace::denoise_points(shot.shot, settings, shot.samples, filter_options(), Progress::silent());
    CHECK(result.over_surfaces);
    CHECK(result.report.rank_decision.kept_modes == 2);
    CHECK(result.filter.width == 0);
    const PointFrames frames = frames_of(result);
    CHECK(rms_error(shot, frames) < 1e-5);
    double largest_sigma = 0;
    for (int t = 0; t < kFrames; ++t)
        for (std::size_t v = 0; v < static_cast<std::size_t>(shot.samples.count()) * 3; ++v)
            largest_sigma = std::max(largest_sigma, static_cast<double>(frames.sigma[t][v]));
    CHECK(largest_sigma < 1e-4);
    double leverage_sum = 0;
    for (double leverage : objectspace::frame_leverages(result.report.temporal_modes, kFrames))
        leverage_sum += leverage;
    CHECK(leverage_sum == doctest::Approx(2.0).epsilon(1e-9));
}

TEST_CASE("point denoise: with noise the surface filter lowers the temporal rebuild's error")
{
    PointShot shot = make_point_shot(0.1);
    objectspace::PointDenoise filtered =
        objectspace::denoise_points(shot.shot, denoise::Settings{}, shot.samples, filter_options(), Progress::silent());
    objectspace::SurfaceFilterOptions off = filter_options();
    off.filter = false;
    objectspace::PointDenoise temporal =
        objectspace::denoise_points(shot.shot, denoise::Settings{}, shot.samples, off, Progress::silent());
    const double error = rms_error(shot, frames_of(filtered)),
                 temporal_error = rms_error(shot, frames_of(temporal));
    MESSAGE("N = " << filtered.report.rank_decision.kept_modes << ", RMS error: noise 0.1, temporal "
                   << temporal_error << ", filtered " << error << " (" << filtered.filter.reasoning << ")");
    CHECK(filtered.report.rank_decision.kept_modes == 2);
    CHECK(temporal_error < 0.1 * std::sqrt(3.0 / kFrames)); // about N/F of the noise variance is kept
    CHECK(filtered.filter.width > 0);
    CHECK(error < 0.6 * temporal_error);
}

TEST_CASE("point denoise: without positions and normals, the engine on the point image with nothing spatial")
{
    PointShot shot = make_point_shot(0.1);
    denoise::Settings settings; // spatial parts on, as an image run might ask: all of them are turned off
    settings.mode_filter.enabled = true;
    settings.sigma_radius = 2;
    objectspace::PointDenoise result = objectspace::denoise_points(shot.shot, settings, objectspace::SurfaceSamples{},
                                                                   filter_options(), Progress::silent());
    CHECK_FALSE(result.over_surfaces);
    CHECK(result.filter.width == 0);

    denoise::Settings plain;
    plain.feature_guide.kinds.clear();
    plain.sigma_radius = 0;
    plain.measured_frame_noise = false; // a point image's rows are not neighbours on the surfaces
    MemorySink sink(shot.shot.size);
    denoise::run_denoise(shot.shot, sink, plain, Progress::silent());
    const PointFrames frames = frames_of(result);
    for (int t = 0; t < kFrames; ++t) {
        CHECK(sink.rebuilt[t] == frames.values[t]);
        CHECK(sink.sigma[t] == frames.sigma[t]);
    }
}

TEST_CASE("point denoise: an input too large to keep is read again, with the same bits, and a budget too "
          "small is refused")
{
    PointShot shot = make_point_shot(0.1);
    const std::int64_t matrix = static_cast<std::int64_t>(shot.shot.size.width) * shot.shot.size.height * 3 *
                                kFrames * static_cast<std::int64_t>(sizeof(float));
    struct CountingSource : denoise::ForwardingSource {
        using ForwardingSource::ForwardingSource;
        void read_rows(int frame, int begin, int end, float* destination,
                       denoise::PassThroughRows* rows) override
        {
            rows_read += end - begin;
            ForwardingSource::read_rows(frame, begin, end, destination, rows);
        }
        std::atomic<std::int64_t> rows_read{0}; // the engine reads frames from several threads
    };
    CountingSource roomy(shot.shot), tight(shot.shot);
    denoise::Settings settings;
    const objectspace::PointDenoise kept =
        objectspace::denoise_points(roomy, settings, shot.samples, filter_options(), Progress::silent());
    // What the result holds besides the matrices: the surface filter's window
    // lists and its arrays for up to 2 modes.
    const std::int64_t filter =
        objectspace::SurfaceFilter::window_neighbours(shot.samples, filter_options()).bytes() +
        objectspace::SurfaceFilter::state_bytes(shot.samples.count(), 3, 2);
    // The rebuild, the input and a matrix's worth for the engine do not fit.
    settings.max_memory_bytes = filter + matrix * 29 / 10;
    const objectspace::PointDenoise streamed =
        objectspace::denoise_points(tight, settings, shot.samples, filter_options(), Progress::silent());
    CHECK(kept.input_kept);
    CHECK_FALSE(streamed.input_kept);
    const std::int64_t engine_rows = roomy.rows_read.load();
    const PointFrames kept_frames = frames_of(kept), streamed_frames = frames_of(streamed);
    CHECK(kept_frames.values == streamed_frames.values);
    CHECK(kept_frames.sigma == streamed_frames.sigma);
    CHECK(roomy.rows_read == engine_rows); // kept: never read again
    // Read again: once for the noise level and once per frame made.
    MESSAGE("rows read: kept " << roomy.rows_read.load() << ", read again " << tight.rows_read.load());
    CHECK(tight.rows_read >= engine_rows + 2 * kFrames * shot.shot.size.height);

    settings.max_memory_bytes = filter + matrix;
    try {
        objectspace::denoise_points(tight, settings, shot.samples, filter_options(), Progress::silent());
        FAIL("a budget that cannot hold the rebuild was taken");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::Usage);
        MESSAGE(std::string(error.what()));
    }
}
