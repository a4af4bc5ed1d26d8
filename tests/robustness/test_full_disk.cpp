// Full disk (issue 12): runs that write into a tiny tmpfs mounted by the test
// (as root; reported skipped, with the reason, otherwise) end with exit 1 and
// one line naming the output file, leave no temporary file, and every file left
// under a final name is complete.
#include "tests/robustness/robustness_kit.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <filesystem>
#include <string>

using namespace modestack;
using namespace modestack::robustness;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kFrames = 12;

float noisy_value(int frame, int x, int y, int c)
{
    return 0.3f + 0.01f * x + 0.05f * c + 0.02f * static_cast<float>(((frame * 131 + x) * 977 + y * 7 + c) % 23);
}

std::vector<int> all_frames()
{
    std::vector<int> frames;
    for (int frame = 1; frame <= kFrames; ++frame)
        frames.push_back(frame);
    return frames;
}

// Runs `arguments` (whose output goes to `tiny`/out) and checks the promise.
void check_full_disk_run(const std::string& arguments, const std::string& tiny, const std::string& reference)
{
    auto result = run_modestack(arguments);
    MESSAGE(result.err);
    CHECK(result.exit_code == 1);
    CHECK(one_line(result.err));
    // The message names the output file (its final name) and says it could not be written.
    CHECK(result.err.find("modestack: " + tiny + "/out/") == 0);
    CHECK(result.err.find("cannot write") != std::string::npos);
    CHECK(temporary_files(tiny).empty());
    for (const std::string& name : final_files(tiny + "/out")) {
        CAPTURE(name);
        CHECK(testkit::read_native(tiny + "/out/" + name) == testkit::read_native(reference + "/" + name));
    }
}

}  // namespace

TEST_CASE("full disk: denoise and render exit 1 naming the output, no temporary file, no partial final file")
{
    TempDir dir;
    TinyFilesystem tiny(dir.path(), "96k");
    if (!tiny.mounted()) {
        testkit::report_skipped(tiny.why_not());
        return;
    }
    testkit::ExrLayout layout;
    layout.width = 64;
    layout.height = 48;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout, noisy_value);
    std::string denoise = "denoise " + dir.file("in.####.exr") + " -q -o ";
    REQUIRE(run_modestack(denoise + dir.file("ref/d.####.exr")).exit_code == 0);
    check_full_disk_run(denoise + tiny.path() + "/out/d.####.exr", tiny.path(), dir.file("ref"));

    // A render writes frame after frame: a few fit (about 100 KB each), then the disk is full.
    TinyFilesystem larger(dir.path() + "/ref", "400k");
    REQUIRE(larger.mounted());
    std::string render = "render --scene switch --size 64x48 --spp 2 --frames 1-12 -q -o ";
    REQUIRE(run_modestack(render + dir.file("refr/r.####.exr")).exit_code == 0);
    check_full_disk_run(render + larger.path() + "/out/r.####.exr", larger.path(), dir.file("refr"));
    CHECK(!final_files(larger.path() + "/out").empty());
}

// OpenEXR only says "File output failed."; the message adds the system's reason.
TEST_CASE("full disk: the message says the disk is full")
{
    TempDir dir;
    TinyFilesystem tiny(dir.path(), "32k");
    if (!tiny.mounted()) {
        testkit::report_skipped(tiny.why_not());
        return;
    }
    auto result = run_modestack("render --scene switch --size 64x48 --spp 1 --frames 1-12 -q -o " + tiny.path() +
                                "/out/r.####.exr");
    CHECK(result.exit_code == 1);
    CHECK(result.err.find("No space left on device") != std::string::npos);
}

TEST_CASE("full disk: a JSON summary that does not fit leaves neither a final nor a temporary file")
{
    TempDir dir;
    TinyFilesystem tiny(dir.path(), "8k");
    if (!tiny.mounted()) {
        testkit::report_skipped(tiny.why_not());
        return;
    }
    testkit::ExrLayout layout;
    layout.width = 8;
    layout.height = 6;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout, noisy_value);
    // Fill the tmpfs, then ask for a JSON description there.
    write_bytes(tiny.path() + "/filler", std::string(4096, 'x'));
    try {
        write_bytes(tiny.path() + "/filler2", std::string(64 * 1024, 'x'));
    } catch (const std::exception&) {
        // expected: the disk is full now
    }
    auto result = run_modestack("info " + dir.file("in.####.exr") + " --all-attributes --json " + tiny.path() +
                                "/out/info.json");
    MESSAGE(result.err);
    CHECK(result.exit_code == 1);
    CHECK(one_line(result.err));
    CHECK(result.err.find(tiny.path() + "/out/info.json") != std::string::npos);
    CHECK(final_files(tiny.path() + "/out").empty());
    CHECK(temporary_files(tiny.path()).empty());
}
