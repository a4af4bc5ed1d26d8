// End-to-end: the real `modestack` binary on real EXR files in a temp dir:
// help, version, usage errors, `info` on a multi-layer sequence, and the
// one-line errors with their exit codes for bad input.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {
testkit::ExrLayout cycles_like()
{
    testkit::ExrLayout layout;
    layout.width = 24;
    layout.height = 10;
    layout.channel_names = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                            "ViewLayer.Combined.A", "ViewLayer.DiffInd.R",  "ViewLayer.DiffInd.G",
                            "ViewLayer.DiffInd.B",  "ViewLayer.Depth.Z"};
    layout.channel_types = {"half", "half", "half", "half", "half", "half", "half", "float"};
    layout.attributes = {{"cycles.ViewLayer.samples", "4"}};
    return layout;
}
float value(int frame, int x, int y, int c) { return 0.1f * (x + y + c) + frame; }

bool one_line(const std::string& text) { return !text.empty() && text.find('\n') == text.size() - 1; }

std::string read_file(const std::string& path)
{
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}
}  // namespace

TEST_CASE("--help on stdout with exit 0, --version, unknown options and subcommands exit 2 with one line")
{
    auto help = run_modestack("--help");
    CHECK(help.exit_code == 0);
    CHECK(help.out.find("info") != std::string::npos);
    auto info_help = run_modestack("info --help");
    CHECK(info_help.exit_code == 0);
    CHECK(info_help.out.find("--json") != std::string::npos);
    auto version = run_modestack("--version");
    CHECK(version.exit_code == 0);
    CHECK(version.out.find("modestack 0.") == 0);
    auto unknown = run_modestack("info --no-such-option x.####.exr");
    CHECK(unknown.exit_code == 2);
    CHECK(one_line(unknown.err));
    CHECK(unknown.err.find("modestack: ") == 0);
    CHECK(run_modestack("frobnicate").exit_code == 2);
    CHECK(run_modestack("").exit_code == 2);
}

TEST_CASE("every option printed by --help is in the man page")
{
    std::string man = read_file(std::string(MODESTACK_SOURCE_DIR) + "/man/modestack.1");
    REQUIRE_FALSE(man.empty());
    std::string main_help = run_modestack("--help").out;
    std::set<std::string> subcommands;
    std::smatch match;
    std::regex subcommand_line(R"(\n  ([a-z]+)\s)");
    for (auto it = main_help.cbegin(); std::regex_search(it, main_help.cend(), match, subcommand_line); it = match[0].second)
        subcommands.insert(match[1]);
    REQUIRE(subcommands.count("info") == 1);
    std::regex option(R"(--[a-z][a-z0-9-]*)");
    for (const std::string& command : subcommands) {
        std::string help = run_modestack(command + " --help").out;
        CHECK_MESSAGE(man.find(".SS " + command) != std::string::npos, "subcommand missing in man page: " << command);
        for (auto it = help.cbegin(); std::regex_search(it, help.cend(), match, option); it = match[0].second) {
            std::string roff = match.str();
            std::string escaped = std::regex_replace(roff, std::regex("-"), "\\-");
            CHECK_MESSAGE(man.find(escaped) != std::string::npos,
                          "modestack " << command << " " << roff << " is not in man/modestack.1");
        }
    }
}

TEST_CASE("info describes a multi-layer sequence: frames, gaps, layers with pixel types, attributes, JSON")
{
    TempDir dir;
    testkit::write_sequence(dir.file("shot.%04d.exr"), {1001, 1002, 1003, 1005}, cycles_like(), value);
    auto result = run_modestack("info " + dir.file("shot.####.exr") + " --json " + dir.file("info.json"));
    REQUIRE(result.exit_code == 0);
    CHECK(result.out.find("1001-1003,1005 (4 frames, first 1001, last 1005)") != std::string::npos);
    CHECK(result.out.find("gaps         1004") != std::string::npos);
    CHECK(result.out.find("data window  24x10") != std::string::npos);
    CHECK(result.out.find("ViewLayer.Combined           R,G,B,A half") != std::string::npos);
    CHECK(result.out.find("ViewLayer.Depth              Z float") != std::string::npos);
    CHECK(result.out.find("cycles.ViewLayer.samples") != std::string::npos);
    auto json = nlohmann::json::parse(read_file(dir.file("info.json")));
    CHECK(json["frame_count"] == 4);
    CHECK(json["gaps"] == std::vector<int>{1004});
    CHECK(json["layers"].size() == 3);
    // EXR stores channels sorted by name; OIIO keeps that order after R,G,B,A.
    CHECK(json["layers"][1]["layer"] == "ViewLayer.Depth");
    CHECK(json["layers"][1]["channels"][0]["type"] == "float");
    CHECK(json["layers"][2]["layer"] == "ViewLayer.DiffInd");
    CHECK(json["data_window"]["width"] == 24);

    auto frames = run_modestack("info " + dir.file("shot.####.exr") + " --frames 1001-1003");
    CHECK(frames.exit_code == 0);
    CHECK(frames.out.find("gaps         none") != std::string::npos);
}

TEST_CASE("info: bad input gets one line naming the file and exit 1, bad usage exit 2")
{
    TempDir dir;
    testkit::write_sequence(dir.file("shot.%04d.exr"), {1, 2}, cycles_like(), value);
    std::ofstream(dir.file("bad.0001.exr")) << "garbage";
    struct Case {
        std::string arguments;
        int exit_code;
        std::string message;
    };
    std::vector<Case> cases{
        {"info " + dir.file("none.####.exr"), 1, "none.####.exr: no frames found on disk"},
        {"info " + dir.file("shot.####.exr") + " --frames 1-3", 1, "shot.0003.exr: frame 3 is missing"},
        {"info " + dir.file("bad.####.exr"), 1, "bad.0001.exr: cannot read image header"},
        {"info " + dir.file("nodir/shot.####.exr"), 1, "nodir: directory does not exist"},
        {"info " + dir.file("shot.exr"), 2, "is not a frame-sequence pattern"},
        {"info " + dir.file("shot.####.exr") + " --frames 3-x", 2, "--frames '3-x': not a frame range"},
        {"info " + dir.file("shot.####.exr") + " --json " + dir.file("shot.0001.exr") + "/x.json", 1,
         "x.json: cannot create file"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack(c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK(one_line(result.err));
        CHECK(result.err.find(c.message) != std::string::npos);
        MESSAGE(result.err);
    }
}
