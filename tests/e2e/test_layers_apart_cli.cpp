// End-to-end: `denoise --layer A --layer B` denoises each layer on its own
// modes and N in one run. On a rendered shot: each layer's pixels and sigma
// equal runs of the layers one after another (DiffDir, then DiffInd on its
// output), --whiten included (DiffInd whitened by its own DiffIndVar, DiffDir,
// which has no variance layer, not), the untouched channels equal the input's
// bits, the JSON summary and the header give each layer's N, --joint shares one
// set of modes as before, and what needs one set of modes (--stage,
// --save-modes, --rank-map) is refused with a one-line usage error naming --joint.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kFrames = 8;

std::string frame_file(const TempDir& dir, const std::string& printf_pattern, int frame)
{
    char name[4096];
    std::snprintf(name, sizeof name, printf_pattern.c_str(), frame);
    return dir.file(name);
}

void run_ok(const std::string& arguments)
{
    const testkit::CliResult result = run_modestack(arguments);
    REQUIRE_MESSAGE(result.exit_code == 0, std::string(arguments + ": " + result.err));
}

std::vector<std::string> rgb_and_sigma(const std::string& layer)
{
    return {layer + ".R",       layer + ".G",       layer + ".B",
            layer + ".sigma.R", layer + ".sigma.G", layer + ".sigma.B"};
}

nlohmann::json load_json(const std::string& path)
{
    return nlohmann::json::parse(testkit::read_text(path));
}

} // namespace

TEST_CASE(
    "denoise --layer A --layer B: each layer on its own modes, whitened on its own variance, the bits of "
    "the layers run one after another")
{
    TempDir dir;
    run_ok("render --scene switch --frames 1-" + std::to_string(kFrames) + " --spp 2 --size 48x36 -q -o " +
           dir.file("in.####.exr"));
    const std::string input = dir.file("in.####.exr");
    // --whiten auto: DiffInd is whitened by its own DiffIndVar, as in a run of it alone.
    run_ok("denoise " + input + " --layer DiffInd --layer DiffDir --whiten auto -q -o " +
           dir.file("both/d.####.exr") + " --json " + dir.file("both.json"));
    // Chained, as `run` did: DiffDir first, then DiffInd on its output.
    run_ok("denoise " + input + " --layer DiffDir --whiten auto -q -o " + dir.file("dir/d.####.exr"));
    run_ok("denoise " + dir.file("dir/d.####.exr") + " --layer DiffInd --whiten auto -q -o " +
           dir.file("chain/d.####.exr") + " --json " + dir.file("chain.json"));
    run_ok("denoise " + input + " --layer DiffInd --layer DiffDir --whiten off -q -o " +
           dir.file("plain/d.####.exr"));
    run_ok("denoise " + input + " --layer DiffInd --layer DiffDir --joint -q -o " +
           dir.file("joint/d.####.exr") + " --json " + dir.file("joint.json"));

    const nlohmann::json both = load_json(dir.file("both.json"));
    CHECK(both["joint"] == false);
    REQUIRE(both["layers"].size() == 2);
    CHECK(both["layers"][0]["layer"] == "DiffInd");
    CHECK(both["layers"][1]["layer"] == "DiffDir");
    const int ind_modes = both["layers"][0]["rank"]["n"], dir_modes = both["layers"][1]["rank"]["n"];
    CHECK(ind_modes >= 1);
    CHECK(dir_modes >= 1);
    CHECK(both["rank"]["n"] == ind_modes); // the top level repeats the first layer's
    // Whitened per layer, each saying why; the top level sums it up.
    CHECK(both["layers"][0]["whiten"]["mode"] == "on");
    CHECK(both["layers"][0]["whiten"]["reason"] == "variance layer");
    CHECK(both["layers"][1]["whiten"]["mode"] == "off");
    CHECK(both["layers"][1]["whiten"]["reason"] == "no variance layer");
    CHECK(both["method"]["whiten"]["mode"] == "per layer");
    CHECK(both["layers"][0]["whiten"]["weight_max"] ==
          load_json(dir.file("chain.json"))["method"]["whiten"]["weight_max"]);
    CHECK(both["renderer"]["layer_variance"][0]["found"] == "DiffIndVar");
    CHECK(both["renderer"]["layer_variance"][1]["found"].is_null());
    const nlohmann::json joint = load_json(dir.file("joint.json"));
    CHECK(joint["joint"] == true);
    CHECK_FALSE(joint["layers"][0].contains("rank"));
    // --joint keeps the rule of one set of modes: whitened only when every layer has a variance.
    CHECK(joint["method"]["whiten"]["mode"] == "off");
    CHECK(joint["method"]["whiten"]["reason"] == "no variance layer");
    CHECK(testkit::read_string_attribute(frame_file(dir, "both/d.%04d.exr", 1), "modestack:layer_ranks") ==
          "DiffInd=" + std::to_string(ind_modes) + ",DiffDir=" + std::to_string(dir_modes));
    CHECK(testkit::read_string_attribute(frame_file(dir, "joint/d.%04d.exr", 1), "modestack:layer_ranks") ==
          "");

    bool joint_differs = false, whitening_changed = false;
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::string out = frame_file(dir, "both/d.%04d.exr", frame);
        const std::string chained = frame_file(dir, "chain/d.%04d.exr", frame);
        CHECK(testkit::read_channels(out, rgb_and_sigma("DiffInd")) ==
              testkit::read_channels(chained, rgb_and_sigma("DiffInd")));
        CHECK(testkit::read_channels(out, rgb_and_sigma("DiffDir")) ==
              testkit::read_channels(chained, rgb_and_sigma("DiffDir")));
        whitening_changed =
            whitening_changed ||
            testkit::read_channels(out, rgb_and_sigma("DiffInd")) !=
                testkit::read_channels(frame_file(dir, "plain/d.%04d.exr", frame), rgb_and_sigma("DiffInd"));
        // Untouched layers pass through bit for bit.
        const std::vector<std::string> untouched{"DiffCol.R", "DiffCol.G", "DiffCol.B", "Emit.R", "Depth.Z"};
        CHECK(testkit::read_channels(out, untouched) ==
              testkit::read_channels(frame_file(dir, "in.%04d.exr", frame), untouched));
        joint_differs =
            joint_differs ||
            testkit::read_channels(out, rgb_and_sigma("DiffDir")) !=
                testkit::read_channels(frame_file(dir, "joint/d.%04d.exr", frame), rgb_and_sigma("DiffDir"));
    }
    CHECK(joint_differs);     // --joint still shares one set of modes
    CHECK(whitening_changed); // DiffInd's weights did something

    // --whiten on wants every layer apart to have a variance: one line naming the file and the names.
    const testkit::CliResult refused =
        run_modestack("denoise " + input + " --layer DiffInd --layer DiffDir --whiten on -q -o " +
                      dir.file("on/d.####.exr"));
    CHECK(refused.exit_code == 1);
    CHECK(refused.err.find(input) != std::string::npos);
    CHECK(refused.err.find("variance layer of DiffDir") != std::string::npos);
    CHECK(refused.err.find("looked for DiffDirVar") != std::string::npos);
    CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
    CHECK_FALSE(std::filesystem::exists(frame_file(dir, "on/d.%04d.exr", 1)));
}

TEST_CASE("denoise with several layers apart refuses what needs one set of modes, naming --joint")
{
    TempDir dir;
    run_ok("render --scene static --frames 1-4 --spp 1 --size 16x12 -q -o " + dir.file("in.####.exr"));
    const std::string layers = "denoise " + dir.file("in.####.exr") + " --layer DiffInd --layer DiffDir -q ";
    for (const std::string& option :
         {"--stage stats --rows 1/2 -o " + dir.file("stats.bin"),
          "--save-modes " + dir.file("modes") + " -o " + dir.file("a/d.####.exr"),
          "--rank-map " + dir.file("rank.exr") + " --estimators rebuild -o " + dir.file("b/d.####.exr")}) {
        CAPTURE(option);
        const testkit::CliResult refused = run_modestack(layers + option);
        CHECK(refused.exit_code == 2);
        CHECK(refused.err.find("--joint") != std::string::npos);
        CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
    }
    CHECK(testkit::list_directory(dir.path()).size() == 4); // nothing written
    const testkit::CliResult joint = run_modestack(layers + "--joint --save-modes " + dir.file("modes") +
                                                   " -o " + dir.file("c/d.####.exr"));
    CHECK_MESSAGE(joint.exit_code == 0, joint.err);
}

TEST_CASE("denoising a denoise output again replaces its layer's sigma channels, never a second set")
{
    TempDir dir;
    run_ok("render --scene orbit --frames 1-6 --spp 2 --size 32x24 -q -o " + dir.file("in.####.exr"));
    run_ok("denoise " + dir.file("in.####.exr") + " --layer DiffInd -q -o " + dir.file("a/d.####.exr"));
    run_ok("denoise " + dir.file("a/d.####.exr") + " --layer DiffInd -q -o " + dir.file("b/d.####.exr"));
    // What the second run computes, written alone (no input channels to collide with).
    run_ok("denoise " + dir.file("a/d.####.exr") +
           " --layer DiffInd --only-denoised --no-update-beauty -q -o " + dir.file("c/d.####.exr"));
    for (int frame = 1; frame <= 6; ++frame) {
        CAPTURE(frame);
        const std::vector<std::string> once =
            testkit::read_channel_names(frame_file(dir, "a/d.%04d.exr", frame));
        const std::vector<std::string> twice =
            testkit::read_channel_names(frame_file(dir, "b/d.%04d.exr", frame));
        CHECK(twice.size() == once.size());
        CHECK(std::set<std::string>(twice.begin(), twice.end()) ==
              std::set<std::string>(once.begin(), once.end()));
        const std::vector<std::string> sigma{"DiffInd.sigma.R", "DiffInd.sigma.G", "DiffInd.sigma.B"};
        CHECK(testkit::read_channels(frame_file(dir, "b/d.%04d.exr", frame), sigma) ==
              testkit::read_channels(frame_file(dir, "c/d.%04d.exr", frame), sigma));
        CHECK(testkit::read_channels(frame_file(dir, "b/d.%04d.exr", frame), sigma) !=
              testkit::read_channels(frame_file(dir, "a/d.%04d.exr", frame), sigma));
    }
}
