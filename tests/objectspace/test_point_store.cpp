// The points kept in memory: KeepingSource hands on its inner source's rows
// unchanged and, once every band was read (in any order, from any thread), holds
// the whole shot; PointStore holds what a sink receives, band by band (sigma
// only when asked).
#include "core/objectspace/point_store.h"
#include "tests/denoise/memory_shot.h"

#include <doctest/doctest.h>
#include <tbb/parallel_for.h>

#include <random>
#include <vector>

using namespace modestack;
using denoise::testing::MemoryShot;

namespace {

MemoryShot random_shot(unsigned seed)
{
    MemoryShot shot;
    shot.size = {5, 7, 6, 3};
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> value(-1.0f, 4.0f);
    for (int t = 0; t < shot.size.frames; ++t) {
        shot.frames.emplace_back(std::size_t(shot.size.width) * shot.size.height * shot.size.channels);
        for (float& v : shot.frames.back())
            v = value(random);
    }
    return shot;
}

} // namespace

TEST_CASE("point store: KeepingSource keeps every row it hands on")
{
    MemoryShot shot = random_shot(1);
    objectspace::KeepingSource keeping(shot);
    CHECK(keeping.shape().frames == shot.size.frames);
    const std::size_t row = std::size_t(shot.size.width) * shot.size.channels;
    // Bands of 2, last band first, frames in parallel.
    tbb::parallel_for(0, shot.size.frames, [&](int t) {
        for (int begin = 4; begin >= 0; begin -= 2) {
            std::vector<float> band(2 * row);
            keeping.read_rows(t, begin, begin + 2, band.data(), nullptr);
            CHECK(std::equal(band.begin(), band.end(), shot.frames[t].begin() + begin * row));
        }
    });
    for (int t = 0; t < shot.size.frames; ++t)
        CHECK(std::equal(shot.frames[t].begin(), shot.frames[t].end(), keeping.frame(t)));
}

TEST_CASE("point store: PointStore holds the values, and sigma when asked, written band by band")
{
    MemoryShot values = random_shot(2), sigma = random_shot(3);
    for (bool keep_sigma : {true, false}) {
        objectspace::PointStore store(values.size, keep_sigma);
        const std::size_t row = std::size_t(values.size.width) * values.size.channels;
        for (int t = 0; t < values.size.frames; ++t)
            for (int begin = 0; begin < values.size.height; begin += 3)
                store.write_rows(t, begin, begin + 3, values.frames[t].data() + begin * row,
                                 sigma.frames[t].data() + begin * row, nullptr);
        for (int t = 0; t < values.size.frames; ++t) {
            CHECK(std::equal(values.frames[t].begin(), values.frames[t].end(), store.values(t)));
            if (keep_sigma)
                CHECK(std::equal(sigma.frames[t].begin(), sigma.frames[t].end(), store.sigma(t)));
            else
                CHECK(store.sigma(t) == nullptr);
        }
    }
}
