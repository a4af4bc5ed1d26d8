// The --report collector around the real engine: its box images are the box
// means, it takes each row once however often and however banded the engine
// reads it, its coefficient images rebuild an exactly low-rank shot from the
// engine's temporal modes (the rank slider's math), and its error estimate is
// σ² / (value² + 0.01).
#include "app/report/denoise_report.h"
#include "app/report/report_collector.h"
#include "core/common/progress.h"
#include "core/denoise/engine.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace modestack;
using namespace modestack::app::report;

namespace {

// Frames of an exactly rank-2 shot (optionally with noise).
class MemorySource : public denoise::FrameSource {
public:
    MemorySource(int width, int height, int frames, float noise) : m_shape{frames, width, height, 3}
    {
        std::mt19937 generator(3);
        std::normal_distribution<float> normal(0.0f, noise);
        for (int t = 0; t < frames; ++t)
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x)
                    for (int c = 0; c < 3; ++c) {
                        float a = 0.5f + 0.3f * std::sin(0.3f * x + c) * std::cos(0.2f * y);
                        float b = x > width / 2 ? 1.0f : 0.1f * c;
                        float weight = std::sin(0.5f * t);
                        m_values.push_back(a * (1.0f + 0.1f * t) + b * weight * weight + (noise > 0 ? normal(generator) : 0.0f));
                    }
    }
    denoise::ShotShape shape() const override { return m_shape; }
    void read_rows(int frame, int row_begin, int row_end, float* destination,
                   denoise::PassThroughRows* /*pass_through*/) override
    {
        const size_t row = static_cast<size_t>(m_shape.width) * 3;
        const float* start = m_values.data() + (static_cast<size_t>(frame) * m_shape.height + row_begin) * row;
        std::copy(start, start + (row_end - row_begin) * row, destination);
    }
    float value(int frame, int x, int y, int c) const
    {
        return m_values[((static_cast<size_t>(frame) * m_shape.height + y) * m_shape.width + x) * 3 + c];
    }

private:
    denoise::ShotShape m_shape;
    std::vector<float> m_values;
};

class NullSink : public denoise::FrameSink {
public:
    void write_rows(int, int, int, const float*, const float*, const denoise::PassThroughRows*) override {}
};

}  // namespace

TEST_CASE("box images average whole and partial boxes")
{
    const int width = 7, height = 5, factor = 3;
    BoxImage box(width, height, 3, factor);
    std::vector<float> row(width * 3);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                row[x * 3 + c] = static_cast<float>(100 * c + 10 * y + x);
        box.add_row(y, row.data());
    }
    LinearImage mean = box.mean();
    REQUIRE(mean.width == 3);
    REQUIRE(mean.height == 2);
    // Box (2, 1): x = 6, y = 3..4 -> values 36 and 46 (channel 0).
    CHECK(mean.rgb[(1 * 3 + 2) * 3 + 0] == doctest::Approx(41.0));
    // Box (0, 0): x 0..2, y 0..2 -> mean x = 1, mean y = 1 -> 11 (+100 for channel 1).
    CHECK(mean.rgb[1] == doctest::Approx(111.0));
    CHECK(box_factor(1920, 480) == 4);
    CHECK(box_factor(1921, 480) == 5);
    CHECK(box_factor(100, 480) == 1);
}

TEST_CASE("the collector takes each row once however often and in whatever bands it is read")
{
    MemorySource source(20, 12, 6, 0.1f);
    NullSink sink;
    CollectorOptions options;
    options.preview_width = 10;
    options.shown_indices = {2};
    Collector once(source, sink, options), twice(source, sink, options);
    std::vector<float> rows(20 * 12 * 3);
    for (int t = 0; t < 6; ++t) {
        once.source().read_rows(t, 0, 12, rows.data(), nullptr);
        twice.source().read_rows(t, 0, 5, rows.data(), nullptr);
        twice.source().read_rows(t, 3, 12, rows.data(), nullptr); // overlapping halo rows
        twice.source().read_rows(t, 0, 12, rows.data(), nullptr); // a second pass
    }
    std::vector<std::vector<double>> mode{{1, 0, 0, 0, 0, 0}};
    CHECK(once.coefficient_images(0, mode)[0].rgb == twice.coefficient_images(0, mode)[0].rgb);
    CHECK(once.shown_frames({1, 2, 3, 4, 5, 6})[0].panels[0].image.rgb ==
          twice.shown_frames({1, 2, 3, 4, 5, 6})[0].panels[0].image.rgb);
    CHECK(once.shown_frames({1, 2, 3, 4, 5, 6})[0].number == 3);
}

TEST_CASE("coefficient images and the engine's preview modes rebuild an exactly rank-2 shot")
{
    const int width = 24, height = 16, frames = 12;
    MemorySource source(width, height, frames, 0.0f);
    NullSink sink;
    CollectorOptions options;
    options.preview_width = width;  // no downsampling: the rebuild must be exact
    Collector collector(source, sink, options);
    denoise::Settings settings;
    settings.rank_rule.rule = lowrank::RankRule::Fixed;
    settings.rank_rule.fixed_modes = 2;
    settings.mode_filter.enabled = false;
    settings.report_modes = 8;
    denoise::Report report = denoise::run_denoise(collector.source(), collector.sink(), settings, Progress::silent());
    // N_max = max(2N, 8), at most F − 1.
    REQUIRE(report.preview_temporal_modes.size() == 8);
    for (size_t j = 0; j < 8; ++j)
        for (size_t k = 0; k < 8; ++k) {
            double dot = 0;
            for (int t = 0; t < frames; ++t)
                dot += report.preview_temporal_modes[j][t] * report.preview_temporal_modes[k][t];
            CHECK(dot == doctest::Approx(j == k ? 1.0 : 0.0).epsilon(1e-9));
        }
    // Fitted to each frame's measured noise: projected on pt / D, rebuilt from D pt.
    REQUIRE(report.frame_scales.size() == static_cast<size_t>(frames));
    std::vector<LinearImage> images = collector.coefficient_images(
        0, scaled_modes(report.preview_temporal_modes, report.frame_scales, false));
    const auto rebuild = scaled_modes(report.preview_temporal_modes, report.frame_scales, true);
    double worst = 0, largest = 0;
    for (int t = 0; t < frames; ++t)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) {
                    size_t at = (static_cast<size_t>(y) * width + x) * 3 + c;
                    double rebuilt = 0;
                    for (int j = 0; j < 2; ++j)
                        rebuilt += images[j].rgb[at] * rebuild[j][t];
                    worst = std::max(worst, std::abs(rebuilt - source.value(t, x, y, c)));
                    largest = std::max(largest, std::abs(static_cast<double>(source.value(t, x, y, c))));
                }
    CHECK(worst < 1e-4 * largest);
    // The estimated error is NaN-free after a run; every frame was written.
    for (double error : collector.estimated_error())
        CHECK(std::isfinite(error));
}

TEST_CASE("the estimated error is the mean of sigma squared over value squared plus 0.01")
{
    MemorySource source(4, 3, 3, 0.0f);
    NullSink sink;
    Collector collector(source, sink, {});
    std::vector<float> rebuilt(4 * 3 * 3, 0.3f), sigma(4 * 3 * 3, 0.05f);
    collector.sink().write_rows(1, 0, 3, rebuilt.data(), sigma.data(), nullptr);
    collector.sink().write_rows(1, 0, 3, rebuilt.data(), sigma.data(), nullptr); // taken once
    std::vector<double> errors = collector.estimated_error();
    CHECK(std::isnan(errors[0]));
    CHECK(errors[1] == doctest::Approx(0.05 * 0.05 / (0.3 * 0.3 + 0.01)));
}

TEST_CASE("the estimator map of a shown frame colours each pixel by its estimator, box-averaged, once a row")
{
    MemorySource source(6, 4, 3, 0.0f);
    NullSink sink;
    CollectorOptions options;
    options.panel_width = 3; // boxes of 2 × 2 pixels
    options.shown_indices = {1};
    Collector collector(source, sink, options);
    // Without choice rows there is no map.
    CHECK(collector.shown_frames({1, 2, 3})[0].panels.size() == 3);
    // Rows 0-1: the left box all rebuild, the middle box half input, the right box all 2 px blur.
    const std::vector<std::uint8_t> top{0, 0, 0, 1, 3, 3, //
                                        0, 0, 0, 1, 3, 3};
    const std::vector<std::uint8_t> bottom(12, 2); // rows 2-3: the 1 px blur
    collector.sink().write_choice_rows(1, 0, 2, top.data());
    collector.sink().write_choice_rows(1, 0, 2, bottom.data()); // a second write of the same rows is ignored
    collector.sink().write_choice_rows(1, 2, 4, bottom.data());
    collector.sink().write_choice_rows(0, 0, 2, bottom.data()); // a frame not shown
    const std::vector<Panel> panels = collector.shown_frames({1, 2, 3})[0].panels;
    REQUIRE(panels.size() == 4);
    CHECK(panels[3].label == kEstimatorMapLabel);
    CHECK(panels[3].absolute);
    const LinearImage& map = panels[3].image;
    REQUIRE(map.width == 3);
    REQUIRE(map.height == 2);
    auto pixel = [&](int x, int y, int c) {
        return map.rgb[(static_cast<size_t>(y) * map.width + x) * 3 + c];
    };
    CHECK(pixel(0, 0, 0) == doctest::Approx(0.35)); // rebuild: grey
    CHECK(pixel(0, 0, 1) == doctest::Approx(0.35));
    CHECK(pixel(1, 0, 0) == doctest::Approx((2 * 0.35 + 2 * 1.0) / 4)); // half rebuild, half input (red)
    CHECK(pixel(1, 0, 1) == doctest::Approx(2 * 0.35 / 4));
    CHECK(pixel(2, 0, 2) == doctest::Approx(1.0)); // 2 px blur: blue
    CHECK(pixel(2, 0, 0) == doctest::Approx(0.0));
    for (int x = 0; x < 3; ++x)
        CHECK(pixel(x, 1, 1) == doctest::Approx(0.8)); // 1 px blur: green
}
