// End to end: `modestack denoise --report` and `modestack run` write the page,
// with N_max ≥ 2N modes in the slider and the parts of --segments; a --report
// path that cannot be written fails first, with one line, exit 1 and nothing written.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::read_text;
using testkit::TempDir;

namespace {

std::string make_shot(const TempDir& dir, int frames)
{
    testkit::ExrLayout layout;
    layout.width = 40;
    layout.height = 24;
    std::vector<int> numbers;
    for (int frame = 1; frame <= frames; ++frame)
        numbers.push_back(frame);
    testkit::write_sequence(dir.file("noisy.%04d.exr"), numbers, layout, [](int frame, int x, int y, int c) {
        std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
        std::normal_distribution<float> noise(0.0f, 0.1f);
        float light = frame > 10 ? 1.0f : 0.3f;  // a switch at frame 11
        return light * (0.3f + 0.4f * x / 40.0f + 0.1f * c) + 0.2f * std::sin(0.3f * frame) * (y > 12) +
               noise(generator);
    });
    return dir.file("noisy.%04d.exr");
}

nlohmann::json page_data(const std::string& html)
{
    const std::string open = "id=\"report-data\">";
    size_t begin = html.find(open);
    REQUIRE(begin != std::string::npos);
    begin += open.size();
    return nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
}

}  // namespace

TEST_CASE("denoise --report writes one self-contained page with the slider's modes and the shown frames")
{
    TempDir dir;
    std::string input = make_shot(dir, 20);
    auto result = run_modestack("denoise " + input + " -o " + dir.file("out/d.####.exr") + " --report " +
                                dir.file("r.html") + " --json " + dir.file("d.json") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    std::string html = read_text(dir.file("r.html"));
    CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
    CHECK(html.find("http://") == std::string::npos);
    CHECK(html.find("https://") == std::string::npos);
    nlohmann::json page = page_data(html);
    nlohmann::json summary = nlohmann::json::parse(read_text(dir.file("d.json")));
    int kept_modes = summary["rank"]["n"];
    REQUIRE(page["segments"].size() == 1);
    CHECK(page["segments"][0]["rank"] == kept_modes);
    CHECK(page["segments"][0]["modes"].size() == std::min(std::max(2 * kept_modes, 8), 19));
    CHECK(page["frames"].size() == 3);
    for (const auto& frame : page["frames"]) // noisy, denoised, sigma and the estimator map
        CHECK(frame["panels"].size() == 4);
    CHECK(html.find(summary["rank"]["reasoning"].get<std::string>().substr(0, 20)) != std::string::npos);
    // Without --report nothing else changes: the JSON's kept temporal modes are N.
    CHECK(summary["temporal_modes"].size() == static_cast<size_t>(kept_modes));
}

TEST_CASE(
    "denoise --report maps each shown frame's estimators, shown as it is, and not with the rebuild alone")
{
    TempDir dir;
    std::string input = make_shot(dir, 20);
    auto result = run_modestack("denoise " + input + " -o " + dir.file("out/d.####.exr") + " --report " +
                                dir.file("r.html") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    nlohmann::json page = page_data(read_text(dir.file("r.html")));
    REQUIRE(page["frames"].size() == 3);
    for (const auto& frame : page["frames"]) {
        REQUIRE(frame["panels"].size() == 4);
        CHECK(frame["panels"][3]["label"].get<std::string>().rfind("estimator map", 0) == 0);
        CHECK(frame["panels"][3]["absolute"] == true);
        CHECK(frame["panels"][1]["absolute"] == false); // light goes through the exposure slider
    }
    auto alone = run_modestack("denoise " + input + " -o " + dir.file("alone/d.####.exr") +
                               " --estimators rebuild --report " + dir.file("alone.html") + " -q");
    REQUIRE_MESSAGE(alone.exit_code == 0, alone.err);
    const nlohmann::json alone_page =
        page_data(read_text(dir.file("alone.html"))); // kept: the loop reads into it
    for (const auto& frame : alone_page["frames"])
        CHECK(frame["panels"].size() == 3);
}

TEST_CASE("denoise --report with --segments shows each part and marks the cut")
{
    TempDir dir;
    std::string input = make_shot(dir, 20);
    auto result = run_modestack("denoise " + input + " -o " + dir.file("out/d.####.exr") + " --segments 1-10,11-20" +
                                " --report " + dir.file("r.html") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    std::string html = read_text(dir.file("r.html"));
    nlohmann::json page = page_data(html);
    REQUIRE(page["segments"].size() == 2);
    CHECK(page["segments"][1]["first"] == 10);
    CHECK(page["segments"][1]["count"] == 10);
    const int kept_modes = page["segments"][1]["rank"];
    CHECK(page["segments"][1]["modes"].size() ==
          std::min(std::max(2 * kept_modes, 8), 9)); // at most F − 1 of the part
    CHECK(html.find(">cut<") != std::string::npos);
}

TEST_CASE("a --report path that cannot be written fails before any work, in one line, exit 1")
{
    TempDir dir;
    std::string input = make_shot(dir, 6);
    {
        std::ofstream blocker(dir.file("blocker"));
    }
    // The error names what is wrong: the file in the way, or the directory given as --report.
    for (auto [report, named] : {std::pair{dir.file("blocker/r.html"), dir.file("blocker")},
                                 std::pair{dir.path(), dir.path()}}) {
        auto result = run_modestack("denoise " + input + " -o " + dir.file("out/d.####.exr") + " --report " + report);
        CHECK(result.exit_code == 1);
        CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);
        CHECK(result.err.find(named + ":") != std::string::npos);
        CHECK(testkit::list_directory(dir.file("out")).empty());  // no frame, no modes
    }
}

TEST_CASE("run writes report.html next to its outputs, with refined frames and refine masks")
{
    TempDir dir;
    auto result = run_modestack("run --scene switch --size 32x24 --frames 30-37 --refine-spp 16 --budget 5 "
                                "--reference-spp 16 -q -o " + dir.file("run"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    std::string html = read_text(dir.file("run/report.html"));
    nlohmann::json page = page_data(html);
    REQUIRE(page["frames"].size() == 3);
    std::vector<std::string> labels;
    for (const auto& panel : page["frames"][0]["panels"])
        labels.push_back(panel["label"]);
    REQUIRE(labels.size() == 6);
    CHECK(std::vector<std::string>(labels.begin(), labels.begin() + 4) ==
          std::vector<std::string>{"noisy", "denoised", "refined", "sigma"});
    CHECK(labels[4].rfind("estimator map", 0) == 0);
    CHECK(labels[5] == "refine mask");
    CHECK(html.find("true (against the reference)") != std::string::npos);
    nlohmann::json summary = nlohmann::json::parse(read_text(dir.file("run/summary.json")));
    CHECK(summary["outputs"]["report"] == dir.file("run/report.html"));
}
