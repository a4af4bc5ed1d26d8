// The other half of the corpus: inputs that look unusual but are legitimate
// (1001-based and stepped ranges, odd and 1×1 sizes, tiled and multi-part
// files, NaN/Inf everywhere, a single frame). Each must succeed and give the
// right output, not an error.
#include "tests/robustness/robustness_kit.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace modestack;
using namespace modestack::robustness;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

float smooth_value(int frame, int x, int y, int c) { return 0.2f + 0.01f * x + 0.02f * y + 0.05f * c + 0.01f * frame; }

testkit::ExrLayout rgb_layout(int width, int height)
{
    testkit::ExrLayout layout;
    layout.width = width;
    layout.height = height;
    return layout;
}

std::vector<std::string> names_for(const std::string& prefix, const std::vector<int>& frames)
{
    std::vector<std::string> names;
    for (int frame : frames)
        names.push_back(frame_file(prefix + ".%04d.exr", frame));
    return names;
}

}  // namespace

TEST_CASE("1001-based and stepped ranges are accepted, and only the frames asked for are written")
{
    TempDir dir;
    testkit::write_sequence(dir.file("late.%04d.exr"), {1001, 1002, 1003, 1004}, rgb_layout(9, 7), smooth_value);
    auto late = run_modestack("denoise " + dir.file("late.####.exr") + " -q -o " + dir.file("a/d.####.exr"));
    REQUIRE_MESSAGE(late.exit_code == 0, late.err);
    CHECK(final_files(dir.file("a")) == names_for("d", {1001, 1002, 1003, 1004}));

    std::vector<int> odd{1, 3, 5, 7, 9};
    testkit::write_sequence(dir.file("odd.%04d.exr"), odd, rgb_layout(9, 7), smooth_value);
    // Without --frames the gaps are an error; --frames 1-9x2 says they are wanted.
    auto gaps = run_modestack("denoise " + dir.file("odd.####.exr") + " -q -o " + dir.file("b/d.####.exr"));
    CHECK(gaps.exit_code == 1);
    CHECK(gaps.err.find("missing frames between 1 and 9: 2-8x2") != std::string::npos);
    auto stepped = run_modestack("denoise " + dir.file("odd.####.exr") + " --frames 1-9x2 -q -o " +
                                 dir.file("b/d.####.exr") + " --json " + dir.file("b.json"));
    REQUIRE_MESSAGE(stepped.exit_code == 0, stepped.err);
    CHECK(final_files(dir.file("b")) == names_for("d", odd));
    auto info = run_modestack("info " + dir.file("odd.####.exr") + " --frames 3-9x3");
    CHECK(info.exit_code == 1);  // 6 is not on disk
    CHECK(info.err.find("odd.0006.exr: frame 6 is missing") != std::string::npos);
    auto compare = run_modestack("compare " + dir.file("odd.####.exr") + " " + dir.file("odd.####.exr") +
                                 " --frames 1-9x4 -q");
    CHECK_MESSAGE(compare.exit_code == 0, compare.err);
    // A range written inside the pattern works like --frames.
    auto embedded = run_modestack("info '" + dir.file("odd.1-9x2#.exr") + "'");
    CHECK_MESSAGE(embedded.exit_code == 0, embedded.err);
    CHECK(embedded.out.find("5 frames") != std::string::npos);
}

TEST_CASE("odd sizes: 257x89 and 1x1 are denoised and rendered at their size")
{
    TempDir dir;
    for (auto [width, height] : {std::pair{257, 89}, std::pair{1, 1}}) {
        std::string name = std::to_string(width) + "x" + std::to_string(height);
        CAPTURE(name);
        testkit::write_sequence(dir.file(name + ".%04d.exr"), {1, 2, 3, 4}, rgb_layout(width, height), smooth_value);
        auto denoised = run_modestack("denoise " + dir.file(name + ".####.exr") + " -q -o " +
                                      dir.file(name + "/d.####.exr"));
        REQUIRE_MESSAGE(denoised.exit_code == 0, denoised.err);
        std::vector<float> rgb = testkit::read_channels(dir.file(name + "/d.0002.exr"), {"R", "G", "B"});
        CHECK(rgb.size() == static_cast<size_t>(width) * height * 3);
        // A smooth, noise-free signal linear in time is rebuilt closely by its modes.
        for (size_t i = 0; i < rgb.size(); i += 37) {
            int x = static_cast<int>(i / 3 % width), y = static_cast<int>(i / 3 / width), c = static_cast<int>(i % 3);
            CHECK(rgb[i] == doctest::Approx(smooth_value(2, x, y, c)).epsilon(0.01));
        }
        auto rendered = run_modestack("render --scene orbit --frames 1 --spp 1 --size " + name + " -q -o " +
                                      dir.file(name + "/r.####.exr"));
        REQUIRE_MESSAGE(rendered.exit_code == 0, rendered.err);
        CHECK(testkit::read_channels(dir.file(name + "/r.0001.exr"), {"Combined.R"}).size() ==
              static_cast<size_t>(width) * height);
    }
}

TEST_CASE("a tiled input (partial edge tiles) gives the same pixels as its scanline copy")
{
    TempDir dir;
    testkit::ExrLayout scanline = rgb_layout(13, 9), tiled = rgb_layout(13, 9);
    tiled.tile_size = 4;
    auto noisy = [](int frame, int x, int y, int c) {
        return smooth_value(frame, x, y, c) + 0.05f * static_cast<float>(((frame * 7 + x) * 13 + y * 5 + c) % 11 - 5);
    };
    testkit::write_sequence(dir.file("scan.%04d.exr"), {1, 2, 3, 4, 5}, scanline, noisy);
    testkit::write_sequence(dir.file("tile.%04d.exr"), {1, 2, 3, 4, 5}, tiled, noisy);
    REQUIRE(run_modestack("denoise " + dir.file("scan.####.exr") + " -q -o " + dir.file("s/d.####.exr")).exit_code == 0);
    REQUIRE(run_modestack("denoise " + dir.file("tile.####.exr") + " -q -o " + dir.file("t/d.####.exr")).exit_code == 0);
    for (int frame : {1, 3, 5}) {
        std::string name = frame_file("/d.%04d.exr", frame);
        CHECK(testkit::read_native(dir.file("s") + name) == testkit::read_native(dir.file("t") + name));
    }
}

TEST_CASE("NaN and Inf everywhere in the layer are counted and replaced: finite output, other channels copied")
{
    TempDir dir;
    testkit::ExrLayout layout = rgb_layout(6, 5);
    layout.channel_names = {"R", "G", "B", "depth.Z"};
    layout.channel_types = {"half", "half", "half", "float"};
    auto value = [](int frame, int x, int y, int c) {
        if (c == 3)
            return static_cast<float>(frame * 100 + y * 6 + x);
        return (x + y + c + frame) % 3 == 0 ? std::nanf("") : ((x + c) % 2 ? INFINITY : -INFINITY);
    };
    testkit::write_sequence(dir.file("nan.%04d.exr"), {1, 2, 3, 4}, layout, value);
    auto result = run_modestack("denoise " + dir.file("nan.####.exr") + " -o " + dir.file("o/d.####.exr") + " --json " +
                                dir.file("s.json"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    CHECK(result.err.find("360 NaN/Inf values") != std::string::npos);  // 6 x 5 pixels x 3 channels x 4 frames: all
    std::ifstream json_file(dir.file("s.json"));
    CHECK(nlohmann::json::parse(json_file)["outliers"]["non_finite"] == 360);
    for (int frame : {1, 4}) {
        std::string output = frame_file(dir.file("o/d.%04d.exr"), frame);
        for (float v : testkit::read_channels(output, {"R", "G", "B"}))
            CHECK(std::isfinite(v));
        CHECK(testkit::read_channels(output, {"depth.Z"}) ==
              testkit::read_channels(frame_file(dir.file("nan.%04d.exr"), frame), {"depth.Z"}));
    }
}

TEST_CASE("a single frame is fine for info and compare, and multi-part files are described by info")
{
    TempDir dir;
    testkit::write_sequence(dir.file("one.%04d.exr"), {42}, rgb_layout(5, 4), smooth_value);
    auto info = run_modestack("info " + dir.file("one.####.exr"));
    CHECK_MESSAGE(info.exit_code == 0, info.err);
    CHECK(info.out.find("42 (1 frames") != std::string::npos);
    auto compare = run_modestack("compare " + dir.file("one.####.exr") + " " + dir.file("one.####.exr") + " -q");
    CHECK_MESSAGE(compare.exit_code == 0, compare.err);
    write_rgb_exr(dir.file("parts.0001.exr"), 5, 4, 0, 0, 3);
    auto parts = run_modestack("info " + dir.file("parts.####.exr"));
    CHECK_MESSAGE(parts.exit_code == 0, parts.err);
    CHECK(parts.out.find("3 parts") != std::string::npos);
}
