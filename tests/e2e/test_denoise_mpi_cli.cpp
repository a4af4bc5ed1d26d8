// End-to-end: `mpirun -n K modestack denoise` (app/mpi_job.h) on a generated
// multi-layer sequence: 2 and 3 ranks (oversubscribed on a 2-core machine)
// write the pixels of one process, every frame once; a rank that fails makes
// the job fail with its error instead of leaving the others waiting.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {
// 200 rows: 4 blocks of 64 rows, so that 3 ranks each get some.
constexpr int kWidth = 24, kHeight = 200, kFrames = 10;

testkit::ExrLayout layout()
{
    testkit::ExrLayout result;
    result.width = kWidth;
    result.height = kHeight;
    result.channel_names = {"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B",
                            "ViewLayer.Depth.Z"};
    result.channel_types = {"float", "float", "float", "float"};
    return result;
}

float noisy_value(int frame, int x, int y, int c)
{
    if (c == 3)
        return 1.0f + 0.01f * y;
    std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.1f);
    const float t = static_cast<float>(frame) / kFrames;
    return 0.5f + 0.3f * std::sin(0.3f * x + c) * std::cos(0.04f * y) * (1 + t) + 0.2f * (y > 90) * t +
           normal(generator);
}

std::vector<int> all_frames()
{
    std::vector<int> frames;
    for (int f = 1; f <= kFrames; ++f)
        frames.push_back(f);
    return frames;
}

// mpirun as CI runs it: as root, more ranks than cores, no shared-memory
// single-copy (containers forbid the ptrace it needs), and a time limit so
// that a hanging job fails the test instead of the suite. Under
// AddressSanitizer, leak checks are off for the ranks: Open MPI leaves its
// allocations to the exit, many in plugins it has unloaded by then, which no
// suppression can name (the same stages run leak-checked in one process in
// test_denoise_stages_cli.cpp).
std::string mpirun(int ranks)
{
    return "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
           "OMPI_MCA_btl_vader_single_copy_mechanism=none ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" "
           "timeout 300 mpirun --oversubscribe -n " +
           std::to_string(ranks);
}
}  // namespace

TEST_CASE("mpirun -n 2 and -n 3: the pixels of one process, every frame written once")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    const std::string in = "denoise " + dir.file("in.####.exr") + " --layer DiffInd -q ";
    auto one = run_modestack(in + "-o " + dir.file("one/d.####.exr"));
    REQUIRE_MESSAGE(one.exit_code == 0, one.err);
    for (int ranks : {2, 3}) {
        CAPTURE(ranks);
        const std::string out = dir.file("mpi" + std::to_string(ranks));
        auto job = testkit::run_modestack_under(mpirun(ranks), in + "-o " + out + "/d.####.exr --json " + out +
                                                                   ".json");
        REQUIRE_MESSAGE(job.exit_code == 0, job.err);
        CHECK(testkit::list_directory(out).size() == kFrames);
        for (int frame = 1; frame <= kFrames; ++frame) {
            char name[32];
            std::snprintf(name, sizeof name, "/d.%04d.exr", frame);
            CAPTURE(frame);
            CHECK(testkit::read_native(out + name) == testkit::read_native(dir.file("one") + name));
        }
        CHECK(testkit::read_text(out + ".json").find("\"stage\": \"write\"") != std::string::npos);
    }
}

TEST_CASE("mpirun: a rank that fails ends the job with its error, not a hang")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    {
        // Frame 4 cut short: the rows near the bottom, which only the last rank's
        // statistics read, cannot be read.
        std::ifstream file(dir.file("in.0004.exr"), std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(file)), {});
        std::ofstream(dir.file("in.0004.exr"), std::ios::binary | std::ios::trunc)
            << bytes.substr(0, bytes.size() * 9 / 10);
    }
    auto job = testkit::run_modestack_under(mpirun(2), "denoise " + dir.file("in.####.exr") +
                                                           " --layer DiffInd -q -o " + dir.file("out/d.####.exr"));
    CHECK(job.exit_code == 1);
    CHECK_MESSAGE(job.err.find("rank 1 of 2: ") != std::string::npos, job.err);
    CHECK_MESSAGE(job.err.find("in.0004.exr") != std::string::npos, job.err);
    if (std::ifstream(dir.file("out")).good())
        CHECK(testkit::list_directory(dir.file("out")).empty());
}
