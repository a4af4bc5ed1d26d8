// The shot stream's bands with their halo (core/denoise/shot_stream.h): a
// streamed band that follows the previous one keeps the rows both share and
// reads only the new ones, and holds exactly what a fresh read and cleaning of
// its rows would (cleaned values, the other channels' rows for the sink).
#include "core/common/progress.h"
#include "core/denoise/shot_stream.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

using namespace modestack;
using namespace modestack::denoise;

namespace {

// A shot in memory that counts the rows it decodes and keeps a few bytes of
// "other channels" per row, naming the frame and row.
struct CountingShot : FrameSource {
    testing::MemoryShot shot;
    std::atomic<std::int64_t> rows_read{0};
    ShotShape shape() const override { return shot.size; }
    void read_rows(int frame, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override
    {
        shot.read_rows(frame, row_begin, row_end, destination, nullptr);
        rows_read += row_end - row_begin;
        if (!pass_through)
            return;
        pass_through->row_begin = row_begin, pass_through->row_end = row_end;
        pass_through->bytes.clear();
        for (int row = row_begin; row < row_end; ++row)
            for (int k = 0; k < 3; ++k)
                pass_through->bytes.push_back(static_cast<unsigned char>(frame * 7 + row * 3 + k));
    }
};

// Noise with fireflies and a few NaNs, so that the cleaning changes rows.
void fill(CountingShot& source, ShotShape shape)
{
    source.shot.size = shape;
    std::mt19937 random(7);
    std::normal_distribution<float> noise(1.0f, 0.1f);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    const std::size_t samples = static_cast<std::size_t>(shape.width) * shape.height * shape.channels;
    for (int t = 0; t < shape.frames; ++t) {
        std::vector<float> frame(samples);
        for (float& value : frame) {
            const float u = uniform(random);
            value = u < 0.01f ? 50.0f : u < 0.012f ? std::numeric_limits<float>::quiet_NaN() : noise(random);
        }
        source.shot.frames.push_back(std::move(frame));
    }
}

struct Walked {
    std::vector<std::vector<float>> bands;                   // each band's rows, every frame
    std::vector<std::vector<PassThroughRows>> pass_throughs; // each band's other channels
    std::int64_t rows_read = 0;                              // in the walk, the first pass aside
};

Walked walk(bool keeps_rows, bool with_pass_through)
{
    const ShotShape shape{6, 5, 61, 2};
    CountingShot source;
    fill(source, shape);
    BandPlan plan;
    plan.band_rows = 16, plan.halo_band_rows = 4, plan.halo_rows = 5, plan.rolls = true;
    const lowrank::OutlierOptions outliers;
    ShotStream stream(source, outliers, plan, Progress::silent());
    stream.for_each_band([](Band&) {}); // the first pass: cleans, counts and marks
    source.rows_read = 0;
    Walked walked;
    Band band;
    for (int row = 0; row < shape.height; row += plan.halo_band_rows) {
        const Band& data = stream.band_with_halo(band, row, std::min(shape.height, row + plan.halo_band_rows),
                                                 with_pass_through, keeps_rows);
        CHECK(data.row_begin == std::max(0, row - plan.halo_rows));
        CHECK(data.row_end == std::min(shape.height, row + plan.halo_band_rows + plan.halo_rows));
        std::vector<float> rows;
        for (int t = 0; t < shape.frames; ++t)
            rows.insert(rows.end(), data.data + t * data.stride, data.data + t * data.stride + data.rows);
        walked.bands.push_back(std::move(rows));
        walked.pass_throughs.push_back(data.pass_through);
    }
    walked.rows_read = source.rows_read;
    return walked;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

} // namespace

TEST_CASE(
    "shot stream: a band that follows the last keeps their shared rows, reads the rest, and holds a fresh "
    "read's bits")
{
    for (bool with_pass_through : {false, true}) {
        CAPTURE(with_pass_through);
        const Walked fresh = walk(false, with_pass_through);
        const Walked rolled = walk(true, with_pass_through);
        REQUIRE(fresh.bands.size() == rolled.bands.size());
        for (std::size_t b = 0; b < fresh.bands.size(); ++b) {
            CAPTURE(b);
            CHECK(same_bits(fresh.bands[b], rolled.bands[b]));
            REQUIRE(fresh.pass_throughs[b].size() == rolled.pass_throughs[b].size());
            for (std::size_t t = 0; t < fresh.pass_throughs[b].size(); ++t) {
                CHECK(fresh.pass_throughs[b][t].row_begin == rolled.pass_throughs[b][t].row_begin);
                CHECK(fresh.pass_throughs[b][t].row_end == rolled.pass_throughs[b][t].row_end);
                CHECK(fresh.pass_throughs[b][t].bytes == rolled.pass_throughs[b][t].bytes);
            }
        }
        // Fresh: every band reads its halo again (16 bands of up to 14 rows).
        // Rolled: each row once, but for the first bands, which grow at the top.
        MESSAGE("rows read: fresh " << fresh.rows_read << ", rolled " << rolled.rows_read);
        CHECK(fresh.rows_read > 2 * rolled.rows_read);
        CHECK(rolled.rows_read <= 6 * (61 + 3 * 14));
    }
}
