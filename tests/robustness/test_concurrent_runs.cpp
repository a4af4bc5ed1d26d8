// Two runs writing the same output sequence at once (a farm re-queues a job
// that is still running). The rule (docs/robustness.md): each run writes its
// own temporary files (named with its process id) and renames each finished
// frame into place, so the last rename wins and every final file is complete;
// both runs succeed. Here: both exit 0, every final file has exactly the pixels
// of a single run, and no temporary file is left.
#include "tests/robustness/robustness_kit.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

using namespace modestack;
using namespace modestack::robustness;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

float noisy_value(int frame, int x, int y, int c)
{
    return 0.4f + 0.004f * x + 0.002f * y * frame + 0.05f * c +
           0.03f * static_cast<float>(((frame * 131 + x) * 977 + y * 7 + c) % 13 - 6);
}

}  // namespace

TEST_CASE("two denoise runs into the same output: both succeed, every final file is a single run's, no temporaries")
{
    TempDir dir;
    std::vector<int> frames;
    for (int frame = 1; frame <= 12; ++frame)
        frames.push_back(frame);
    testkit::ExrLayout layout;
    layout.width = 64;
    layout.height = 48;
    testkit::write_sequence(dir.file("in.%04d.exr"), frames, layout, noisy_value);
    std::string denoise = "denoise " + dir.file("in.####.exr") + " -q --threads 1 -o ";
    REQUIRE(run_modestack(denoise + dir.file("ref/d.####.exr")).exit_code == 0);

    for (const char* extra : {"", " --skip-existing"}) {
        CAPTURE(extra);
        std::string out = dir.file(std::string("out") + (*extra ? "-skip" : ""));
        BackgroundRun first(denoise + out + "/d.####.exr" + extra, dir.file("err1"));
        BackgroundRun second(denoise + out + "/d.####.exr" + extra, dir.file("err2"));
        int first_code = first.wait(), second_code = second.wait();
        CHECK_MESSAGE(first_code == 0, read_bytes(dir.file("err1")));
        CHECK_MESSAGE(second_code == 0, read_bytes(dir.file("err2")));
        CHECK(temporary_files(out).empty());
        REQUIRE(final_files(out) == final_files(dir.file("ref")));
        for (const std::string& name : final_files(out)) {
            CAPTURE(name);
            CHECK(testkit::read_native(out + "/" + name) == testkit::read_native(dir.file("ref/" + name)));
        }
    }
}
