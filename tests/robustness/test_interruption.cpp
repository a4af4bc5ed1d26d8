// Interruption (issue 12): SIGINT and SIGTERM stop a run promptly with exit
// 130/143 and remove its temporary files; SIGKILL may leave temporary files but
// never a final-named file that is incomplete; and a re-run with
// --skip-existing completes the shot with the pixels of an uninterrupted run
// and removes the temporaries the killed run left. Each run is held by the
// pause hook (robustness_kit.h, PausePoint) where it is writing until the test
// has signalled it, so every signal lands there whatever the machine's speed.
#include "tests/robustness/robustness_kit.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <chrono>
#include <csignal>

using namespace modestack;
using namespace modestack::robustness;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kFrames = 16;

float noisy_value(int frame, int x, int y, int c)
{
    float noise = 0.02f * static_cast<float>(((frame * 131 + x) * 977 + y * 7 + c) % 17 - 8);
    return 0.3f + 0.002f * x + 0.003f * y * (1.0f + 0.02f * frame) + 0.05f * c + noise;
}

std::vector<int> all_frames()
{
    std::vector<int> frames;
    for (int frame = 1; frame <= kFrames; ++frame)
        frames.push_back(frame);
    return frames;
}

// Every final-named file in `directory` has the pixels of the same file in `reference`.
void check_complete(const std::string& directory, const std::string& reference)
{
    for (const std::string& name : final_files(directory)) {
        CAPTURE(name);
        CHECK(testkit::read_native(directory + "/" + name) == testkit::read_native(reference + "/" + name));
    }
}

}  // namespace

TEST_CASE("denoise: SIGINT/SIGTERM exit 130/143 leaving nothing, SIGKILL leaves no partial final file, "
          "--skip-existing completes the shot")
{
    TempDir dir;
    // 272 rows: pass 2 writes in three bands of at most 128 rows, and a band after
    // the held one checks the cancel flag (a signal during the last band's writes
    // lets the run finish).
    testkit::ExrLayout layout;
    layout.width = 96;
    layout.height = 272;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout, noisy_value);
    std::string input = "denoise " + dir.file("in.####.exr") + " -q --threads 2 -o ";
    auto reference = run_modestack(input + dir.file("ref/d.####.exr"));
    REQUIRE_MESSAGE(reference.exit_code == 0, reference.err);
    REQUIRE(final_files(dir.file("ref")).size() == kFrames);

    for (int signal_number : {SIGINT, SIGTERM, SIGKILL}) {
        CAPTURE(signal_number);
        std::string out = dir.file("out" + std::to_string(signal_number));
        // Held before its first ZIP chunk: every output is open under its temporary
        // name. One thread, so that no other thread finishes the shot meanwhile.
        PausePoint writing("libdeflate_zlib_compress:1", dir.file("pause" + std::to_string(signal_number)));
        BackgroundRun run("denoise " + dir.file("in.####.exr") + " -q --threads 1 -o " + out + "/d.####.exr",
                          dir.file("err"), writing.environment());
        REQUIRE(writing.wait_until_held(run));
        CHECK(!temporary_files(out).empty());
        auto signalled = Clock::now();
        run.signal(signal_number);
        writing.release();
        int code = run.wait();
        double seconds = std::chrono::duration<double>(Clock::now() - signalled).count();
        MESSAGE("signal " << signal_number << ": exit " << code << " after " << seconds << " s, "
                          << final_files(out).size() << " final and " << temporary_files(out).size()
                          << " temporary files left");
        CHECK(code == 128 + signal_number);
        CHECK(seconds < 10.0);  // promptly: workers poll the cancel flag between tiles
        if (signal_number != SIGKILL) {
            std::string err = read_bytes(dir.file("err"));
            CHECK_MESSAGE(one_line(err), err);
            CHECK(err.find("interrupted") != std::string::npos);
            CHECK(temporary_files(out).empty());
        }
        // Whatever has a final name is complete (outputs are renamed into place only when finished).
        check_complete(out, dir.file("ref"));

        // The re-run also removes what the killed run left: its process is gone.
        auto rerun = run_modestack(input + out + "/d.####.exr --skip-existing");
        REQUIRE_MESSAGE(rerun.exit_code == 0, rerun.err);
        CHECK(final_files(out) == final_files(dir.file("ref")));
        CHECK(temporary_files(out).empty());
        check_complete(out, dir.file("ref"));
    }
}

TEST_CASE("render: SIGINT/SIGTERM between frames exit 130/143 leaving no temporary file, SIGKILL no partial "
          "frame, --skip-existing renders only the missing frames")
{
    TempDir dir;
    std::string render = "render --scene switch --size 96x72 --spp 8 --frames 1-24 -q --threads 2 -o ";
    auto reference = run_modestack(render + dir.file("ref/r.####.exr"));
    REQUIRE_MESSAGE(reference.exit_code == 0, reference.err);
    for (int signal_number : {SIGINT, SIGTERM, SIGKILL}) {
        CAPTURE(signal_number);
        std::string out = dir.file("out" + std::to_string(signal_number));
        // Held once the second frame is renamed into place: interrupted in the middle of the shot.
        PausePoint second_frame("rename:2", dir.file("pause" + std::to_string(signal_number)));
        BackgroundRun run(render + out + "/r.####.exr", dir.file("err"), second_frame.environment());
        REQUIRE(second_frame.wait_until_held(run));
        run.signal(signal_number);
        second_frame.release();
        int code = run.wait();
        size_t finished = final_files(out).size();
        MESSAGE("signal " << signal_number << ": exit " << code << ", " << finished << " of 24 frames finished");
        CHECK(code == 128 + signal_number);
        CHECK(finished == 2);
        if (signal_number != SIGKILL) {
            CHECK(one_line(read_bytes(dir.file("err"))));
            CHECK(temporary_files(out).empty());
        }
        check_complete(out, dir.file("ref"));

        // The re-run renders only what is missing; its JSON names the frames it skipped.
        auto rerun = run_modestack(render + out + "/r.####.exr --skip-existing --json " + out + ".json");
        REQUIRE_MESSAGE(rerun.exit_code == 0, rerun.err);
        CHECK(final_files(out) == final_files(dir.file("ref")));
        CHECK(temporary_files(out).empty());
        check_complete(out, dir.file("ref"));
        std::string summary = read_bytes(out + ".json");
        CHECK(summary.find("\"skipped_existing_frames\": \"\"") == std::string::npos);
    }
}

TEST_CASE("render --skip-existing with every frame present renders nothing and says so")
{
    TempDir dir;
    std::string render = "render --scene switch --size 32x24 --spp 1 --frames 1-3 --threads 2 -o " +
                         dir.file("r.####.exr");
    REQUIRE(run_modestack(render + " -q").exit_code == 0);
    std::string before = read_bytes(dir.file("r.0002.exr"));
    auto rerun = run_modestack(render + " --skip-existing");
    REQUIRE_MESSAGE(rerun.exit_code == 0, rerun.err);
    CHECK(rerun.err.find("nothing to do") != std::string::npos);
    CHECK(read_bytes(dir.file("r.0002.exr")) == before);
}
