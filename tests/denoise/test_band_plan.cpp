// The memory plan (core/denoise/band_plan.h): the whole shot is kept whenever it
// fits beside a minimal pass 2, otherwise it streams; the chosen bands are the
// largest that fit, multiples of the Gram chunk (or the whole height), and the
// estimate never exceeds the budget; a budget below one band is a usage error
// that names what a band needs.
#include "core/common/error.h"
#include "core/denoise/band_plan.h"

#include <doctest/doctest.h>

#include <cstdint>
#include <string>

using namespace modestack;
using namespace modestack::denoise;

namespace {

// A 1080p-wide shot of 100 frames with the default mode filter's needs on 2 threads.
const ShotShape kShape{100, 1920, 1080, 3};

PassNeeds filter_needs()
{
    PassNeeds needs;
    needs.halo_rows = 11;
    needs.sigma_halo_rows = 4;
    needs.halo_images = 8 + 6;
    needs.band_images = 2 * 8 + 2 + 4 * 2;
    needs.source_row_bytes = 1920 * 3 * 2 * 100;  // a half per selected sample, every frame
    return needs;
}

void check_plan_is_sound(const BandPlan& plan, std::int64_t budget)
{
    CHECK(plan.budget_bytes == budget);
    CHECK(plan.estimated_bytes <= budget);
    CHECK(plan.band_rows > 0);
    CHECK((plan.band_rows % kChunkRows == 0 || plan.band_rows == kShape.height));
    CHECK(plan.halo_rows == filter_needs().halo_rows);
    CHECK(plan.halo_band_rows > 0);
    CHECK(plan.halo_band_rows <= plan.band_rows);
    if (plan.halo_band_rows < plan.band_rows)
        CHECK(plan.band_rows == kChunkRows);
}

}  // namespace

TEST_CASE("band plan: the shot is kept when it fits beside a minimal pass 2, with bands of at most 128 rows")
{
    const std::int64_t kept = input_bytes_per_row(kShape) * kShape.height;
    const std::int64_t minimal = kept + pass_two_bytes(kShape, filter_needs(), kChunkRows, true);
    const BandPlan just = plan_bands(kShape, minimal, filter_needs());
    CHECK(just.in_memory);
    CHECK(just.band_rows == kChunkRows);
    CHECK(just.estimated_bytes == minimal);
    check_plan_is_sound(just, minimal);

    const BandPlan roomy = plan_bands(kShape, std::int64_t(64) << 30, filter_needs());
    CHECK(roomy.in_memory);
    CHECK(roomy.band_rows == kMaxKeptBandRows);
    check_plan_is_sound(roomy, std::int64_t(64) << 30);

    const BandPlan below = plan_bands(kShape, minimal - 1, filter_needs());
    CHECK_FALSE(below.in_memory);
    check_plan_is_sound(below, minimal - 1);
}

TEST_CASE("band plan: streamed bands are the largest that fit and grow with the budget")
{
    int previous_rows = 0;
    std::int64_t previous_estimate = 0;
    for (std::int64_t mebibytes = 512; mebibytes <= 2048; mebibytes += 128) {
        const std::int64_t budget = mebibytes << 20;
        const BandPlan plan = plan_bands(kShape, budget, filter_needs());
        CAPTURE(mebibytes);
        check_plan_is_sound(plan, budget);
        if (plan.in_memory)
            break;
        CHECK(plan.band_rows >= previous_rows);
        CHECK(plan.estimated_bytes >= previous_estimate);
        // One more chunk of rows would not have fitted.
        if (plan.band_rows + kChunkRows <= kShape.height) {
            const BandPlan smaller = plan_bands(kShape, plan.estimated_bytes, filter_needs());
            CHECK(smaller.band_rows == plan.band_rows);
            CHECK(smaller.estimated_bytes == plan.estimated_bytes);
            const std::int64_t grown_pass_two =
                pass_two_bytes(kShape, filter_needs(), plan.band_rows + kChunkRows, false);
            CHECK(grown_pass_two > pass_two_bytes(kShape, filter_needs(), plan.band_rows, false));
            const BandPlan tighter = plan_bands(kShape, plan.estimated_bytes - 1, filter_needs());
            CHECK(tighter.band_rows < plan.band_rows);
        }
        previous_rows = plan.band_rows;
        previous_estimate = plan.estimated_bytes;
    }
    CHECK(previous_rows >= kChunkRows);
}

TEST_CASE("band plan: a kept shot holds sigma apart, a streamed band in its own input rows")
{
    const PassNeeds needs = filter_needs();
    const std::int64_t frame_rows = static_cast<std::int64_t>(kShape.frames) * kShape.width * kShape.channels * 4;
    CHECK(pass_two_bytes(kShape, needs, 32, true) - pass_two_bytes(kShape, needs, 32, false) == 32 * frame_rows);
    // The unfiltered rebuild covers the band and sigma's halo only, not the filter's wider halo.
    PassNeeds wider = needs;
    wider.halo_rows += 10;
    wider.halo_images = 0;
    PassNeeds narrow = needs;
    narrow.halo_images = 0;
    CHECK(pass_two_bytes(kShape, wider, 32, false) == pass_two_bytes(kShape, narrow, 32, false));
}

TEST_CASE(
    "band plan: below a band of a Gram chunk, the passes with a halo walk the longest shorter bands that fit")
{
    const PassNeeds needs = filter_needs();
    // Just below what a 16-row band needs: 15-row bands for the halo passes.
    std::int64_t sixteen = 0;
    for (std::int64_t budget = std::int64_t(2048) << 20;; budget -= std::int64_t(1) << 20) {
        const BandPlan plan = plan_bands(kShape, budget, needs);
        if (plan.halo_band_rows < kChunkRows) {
            check_plan_is_sound(plan, budget);
            CHECK(plan.band_rows == kChunkRows);
            CHECK(plan.halo_band_rows == kChunkRows - 1);
            break;
        }
        sixteen = plan.estimated_bytes;
    }
    // Each row fewer fits a smaller budget, down to one row; below that a usage error.
    int previous = kChunkRows;
    std::int64_t budget = sixteen - 1;
    for (;;) {
        BandPlan plan;
        try {
            plan = plan_bands(kShape, budget, needs);
        } catch (const Error& error) {
            CHECK(previous == 1);
            CHECK(std::string(error.what()).find("of 1 row") != std::string::npos);
            break;
        }
        check_plan_is_sound(plan, budget);
        CHECK(plan.halo_band_rows < previous);
        previous = plan.halo_band_rows;
        budget = plan.estimated_bytes - 1; // the same plan's estimate: one row fewer must follow
    }
}

TEST_CASE("band plan: a budget below one band is a usage error naming what a band needs")
{
    try {
        plan_bands(kShape, std::int64_t(64) << 20, filter_needs());
        FAIL("expected a usage error");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::Usage);
        const std::string what = error.what();
        CHECK(what.find("--max-memory") != std::string::npos);
        CHECK(what.find("a band of 16 rows needs") != std::string::npos);
    }
    // A shot shorter than a chunk plans one band of its own height.
    const ShotShape short_shot{10, 64, 5, 3};
    const BandPlan plan = plan_bands(short_shot, std::int64_t(1) << 30, filter_needs());
    CHECK(plan.in_memory);
    CHECK(plan.band_rows == 5);
}

TEST_CASE("band plan: the survey's own images count only where they exceed pass 2's, never on top of them")
{
    const PassNeeds needs = filter_needs();
    const std::int64_t image_row = static_cast<std::int64_t>(kShape.width) * kShape.channels * 4;
    const std::int64_t halo_band = 32 + 2 * needs.halo_rows;
    // 16 survey images over 54 rows: far below 100 frames over sigma's 40 rows.
    PassNeeds small = needs;
    small.survey_images = 16;
    CHECK(pass_two_bytes(kShape, small, 32, false) == pass_two_bytes(kShape, needs, 32, false));
    // A short shot: its survey copy is the larger, and then it alone is counted.
    const ShotShape few{6, 1920, 1080, 3};
    PassNeeds large = needs;
    large.survey_images = 40;
    const std::int64_t without = pass_two_bytes(few, needs, 32, false);
    const std::int64_t with = pass_two_bytes(few, large, 32, false);
    const std::int64_t pass_two_only = without - needs.halo_images * halo_band * image_row;
    CHECK(with - without == 40 * halo_band * image_row - pass_two_only);
}
