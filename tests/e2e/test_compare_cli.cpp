// End-to-end: `modestack compare` on generated EXR sequences: zero error and
// PASS on identical shots, the closed-form relMSE/PSNR/flicker of known
// perturbations (expectations computed here from the pixel values, not by the
// library), idiff's verdicts and exit codes for each threshold, the distinct
// codes for different sizes, missing or unreadable input and bad usage, and
// Cycles-style multi-layer files with --layer.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::read_text;
using testkit::TempDir;

namespace {
constexpr int kWidth = 12, kHeight = 10, kFrames = 4;

// A reference that changes over time. Multiples of 1/64 below 4: exact in half and float.
float reference_value(int frame, int x, int y, int c)
{
    return static_cast<float>((x * 3 + y * 5 + c * 7 + frame * 11) % 64) / 32.0f + 0.125f;
}

testkit::ExrLayout float_rgb(int width = kWidth, int height = kHeight)
{
    testkit::ExrLayout layout;
    layout.width = width;
    layout.height = height;
    layout.channel_types = {"float", "float", "float"};
    return layout;
}

std::vector<int> frames()
{
    return {1, 2, 3, 4};
}

bool one_line(const std::string& text)
{
    return !text.empty() && text.find('\n') == text.size() - 1;
}

double tonemap(double v)
{
    return v <= 0 ? 0.0 : std::pow(v / (1.0 + v), 1.0 / 2.2);
}

// The figures of docs/design.md, "How quality is measured", computed directly
// from two pixel functions.
struct Expected {
    double relative_mse = 0, psnr = 0, flicker = 0;
};
Expected expected(const testkit::PixelFunction& test, const testkit::PixelFunction& reference)
{
    double relative = 0, tonemapped = 0, flicker = 0;
    for (int f = 1; f <= kFrames; ++f)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c) {
                    double a = test(f, x, y, c), r = reference(f, x, y, c);
                    relative += (a - r) * (a - r) / (r * r + 0.01);
                    tonemapped += std::pow(tonemap(a) - tonemap(r), 2);
                    if (f > 1) {
                        double a0 = test(f - 1, x, y, c), r0 = reference(f - 1, x, y, c);
                        double change = (a - a0) - (r - r0);
                        flicker += change * change / (std::pow((r + r0) / 2, 2) + 0.01);
                    }
                }
    double values = double(kFrames) * kWidth * kHeight * 3;
    return {relative / values, 10 * std::log10(values / tonemapped),
            flicker / (values * (kFrames - 1) / kFrames)};
}

// Writes reference and test sequences and returns "A B" for the command line.
std::string write_pair(const TempDir& dir, const testkit::PixelFunction& test)
{
    testkit::write_sequence(dir.file("ref.%04d.exr"), frames(), float_rgb(), reference_value);
    testkit::write_sequence(dir.file("test.%04d.exr"), frames(), float_rgb(), test);
    return dir.file("test.####.exr") + " " + dir.file("ref.####.exr");
}
} // namespace

TEST_CASE("compare: identical sequences have zero error, PASS and exit 0")
{
    TempDir dir;
    std::string pair = write_pair(dir, reference_value);
    auto result = run_modestack("compare " + pair + " --json " + dir.file("c.json"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    CHECK(result.out.find("\nPASS\n") != std::string::npos);
    auto json = nlohmann::json::parse(read_text(dir.file("c.json")));
    CHECK(json["verdict"] == "PASS");
    CHECK(json["exit_code"] == 0);
    CHECK(json["shot"]["relative_mse"] == 0.0);
    CHECK(json["shot"]["max_absolute_error"] == 0.0);
    CHECK(json["shot"]["flicker"] == 0.0);
    CHECK(json["shot"]["psnr_db"].is_null()); // +inf: JSON has no infinity
    CHECK(json["shot"]["pixels"] == kFrames * kWidth * kHeight);
    REQUIRE(json["per_frame"].size() == static_cast<size_t>(kFrames));
    CHECK(json["per_frame"][0]["flicker"].is_null()); // the first frame has no previous one
    CHECK(json["per_frame"][1]["flicker"] == 0.0);
    CHECK(json["frames"] == frames());
}

TEST_CASE("compare: a known perturbation gives the expected relMSE, PSNR and flicker to 1e-6")
{
    TempDir dir;
    // Every fourth value is off by a frame-dependent amount (multiples of 1/64).
    auto test = [](int f, int x, int y, int c) {
        float r = reference_value(f, x, y, c);
        return (x + y + c) % 4 == 0 ? r + static_cast<float>(f % 3 + 1) / 64.0f : r;
    };
    Expected want = expected(test, reference_value);
    auto result = run_modestack("compare " + write_pair(dir, test) + " --json " + dir.file("c.json"));
    CHECK(result.exit_code == 2);
    auto json = nlohmann::json::parse(read_text(dir.file("c.json")));
    double relative = json["shot"]["relative_mse"], psnr = json["shot"]["psnr_db"],
           flicker = json["shot"]["flicker"];
    MESSAGE("relMSE " << relative << " (expected " << want.relative_mse << "), PSNR " << psnr << " ("
                      << want.psnr << "), flicker " << flicker << " (" << want.flicker << ")");
    CHECK(std::abs(relative - want.relative_mse) < 1e-6 * want.relative_mse);
    CHECK(std::abs(psnr - want.psnr) < 1e-6);
    CHECK(std::abs(flicker - want.flicker) < 1e-6 * want.flicker);
    CHECK(json["shot"]["max_absolute_error"] == 3.0 / 64.0);
    // The table shows every frame and the shot.
    CHECK(result.out.find("relMSE") != std::string::npos);
    CHECK(result.out.find("\n  shot ") != std::string::npos);
    CHECK(result.out.find("\nFAILURE\n") != std::string::npos);
}

TEST_CASE("compare: flicker is zero for a constant offset over time and positive for alternating noise")
{
    TempDir dir;
    auto offset = [](int f, int x, int y, int c) { return reference_value(f, x, y, c) + 0.25f; };
    auto alternating = [](int f, int x, int y, int c) {
        return reference_value(f, x, y, c) + ((f + x + y) % 2 ? 0.25f : -0.25f);
    };
    testkit::write_sequence(dir.file("ref.%04d.exr"), frames(), float_rgb(), reference_value);
    testkit::write_sequence(dir.file("offset.%04d.exr"), frames(), float_rgb(), offset);
    testkit::write_sequence(dir.file("alternating.%04d.exr"), frames(), float_rgb(), alternating);
    auto run = [&](const std::string& name) {
        auto result = run_modestack("compare " + dir.file(name + ".####.exr") + " " +
                                    dir.file("ref.####.exr") + " -q --json " + dir.file(name + ".json"));
        CHECK(result.exit_code == 2);
        return nlohmann::json::parse(read_text(dir.file(name + ".json")));
    };
    auto constant = run("offset"), noisy = run("alternating");
    // The same per-value error size, so a per-frame metric cannot tell them apart...
    CHECK(constant["shot"]["mean_absolute_error"] == 0.25);
    CHECK(noisy["shot"]["mean_absolute_error"] == 0.25);
    // ...but only the alternating one changes from frame to frame.
    CHECK(constant["shot"]["flicker"] == 0.0);
    double want = expected(alternating, reference_value).flicker;
    CHECK(double(noisy["shot"]["flicker"]) > 0.1);
    CHECK(std::abs(double(noisy["shot"]["flicker"]) - want) < 1e-6 * want);
}

TEST_CASE("compare: thresholds give idiff's verdicts and exit codes 0, 1, 2")
{
    TempDir dir;
    // One pixel of one frame (1 of 120 pixels = 0.83 %) is off by 1/64 = 0.015625 in one channel.
    auto test = [](int f, int x, int y, int c) {
        float r = reference_value(f, x, y, c);
        return f == 3 && x == 5 && y == 4 && c == 1 ? r + 1.0f / 64.0f : r;
    };
    std::string pair = write_pair(dir, test);
    struct Case {
        std::string options;
        int exit_code;
        std::string verdict;
    };
    std::vector<Case> cases{
        {"", 2, "FAILURE"}, // idiff's defaults: any pixel over 1e-6 fails
        {"--fail 0.02 --warn 0.01", 1, "WARNING"},
        {"--fail 0.02 --warn 0.02", 0, "PASS"},
        {"--fail 0.015625 --warn 0.015625", 0, "PASS"}, // strictly over the threshold
        {"--fail-percent 1", 1, "WARNING"},             // 0.83 % fail: allowed; warns at 0 %
        {"--fail-percent 1 --warn-percent 1", 0, "PASS"},
        {"--fail-percent 0.8 --warn-percent 1", 2, "FAILURE"},
        {"--fail-percent 1 --warn-percent 1 --hard-fail 0.01", 2, "FAILURE"},
        {"--fail-percent 1 --warn-percent 1 --hard-warn 0.01", 1, "WARNING"},
        {"--frames 1-2", 0, "PASS"}, // the wrong pixel is in frame 3
    };
    for (const Case& c : cases) {
        CAPTURE(c.options);
        auto result = run_modestack("compare " + pair + " -q " + c.options);
        CHECK(result.exit_code == c.exit_code);
        CHECK(result.out == c.verdict + "\n"); // -q: the verdict line only
        CHECK(result.err.empty());
    }
    auto table = run_modestack("compare " + pair + " --fail 0.02 --warn 0.01");
    CHECK(table.exit_code == 1);
    CHECK(table.out.find("     3 ") != std::string::npos);
    CHECK(table.out.find("0 of 4 frames fail, 1 warn, 3 pass") != std::string::npos);
}

TEST_CASE("compare: different sizes or channels exit 3, missing or unreadable input 4, bad usage 5, each "
          "with one line")
{
    TempDir dir;
    testkit::write_sequence(dir.file("ref.%04d.exr"), frames(), float_rgb(), reference_value);
    testkit::write_sequence(dir.file("big.%04d.exr"), frames(), float_rgb(kWidth + 4, kHeight),
                            reference_value);
    testkit::write_sequence(dir.file("short.%04d.exr"), {1, 2}, float_rgb(), reference_value);
    testkit::ExrLayout rgb = float_rgb(), rg = float_rgb();
    rgb.channel_names = {"DiffInd.R", "DiffInd.G", "DiffInd.B"};
    rg.channel_names = {"DiffInd.R", "DiffInd.G"};
    rg.channel_types = {"float", "float"};
    testkit::write_sequence(dir.file("rgb.%04d.exr"), frames(), rgb, reference_value);
    testkit::write_sequence(dir.file("rg.%04d.exr"), frames(), rg, reference_value);
    testkit::write_sequence(dir.file("bad.%04d.exr"), frames(), float_rgb(), reference_value);
    std::ofstream(dir.file("bad.0003.exr"), std::ios::trunc) << "garbage";
    std::string ref = dir.file("ref.####.exr");
    struct Case {
        std::string arguments;
        int exit_code;
        std::string message;
    };
    std::vector<Case> cases{
        {dir.file("big.####.exr") + " " + ref, 3, "data window 16x10 differs from the reference's 12x10"},
        {ref + " " + dir.file("big.####.exr"), 3, "data window 12x10 differs"},
        {dir.file("rg.####.exr") + " " + dir.file("rgb.####.exr") + " --layer DiffInd", 3,
         "channels DiffInd.R,DiffInd.G do not match the reference's DiffInd.R,DiffInd.G,DiffInd.B"},
        {ref + " " + ref + " --layer Nope", 4, "Nope"},
        {ref + " " + dir.file("short.####.exr"), 4, "short.0003.exr: frame 3 is missing"},
        {dir.file("none.####.exr") + " " + ref, 4, "none.####.exr: no frames found on disk"},
        {dir.file("bad.####.exr") + " " + ref, 4, "bad.0003.exr"},
        {ref + " " + ref + " --json " + dir.file("ref.0001.exr") + "/x.json", 4,
         "output directory is a file"},
        {ref + " " + ref + " --no-such-option", 5, "--no-such-option"},
        {ref, 5, "SEQ_B"},
        {ref + " " + ref + " --fail-percent 150", 5, "--fail-percent"},
        {ref + " " + ref + " --fail -1", 5, "--fail"},
        {dir.file("ref.0001.exr") + " " + ref, 5, "is not a frame-sequence pattern"},
        {ref + " " + ref + " --frames 2-x", 5, "--frames '2-x'"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack("compare " + c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK(one_line(result.err));
        CHECK(result.err.find("modestack: ") == 0);
        CHECK(result.err.find(c.message) != std::string::npos);
        MESSAGE(result.err);
    }
    // The other subcommands keep their own usage code.
    CHECK(run_modestack("info --no-such-option " + ref).exit_code == 2);
}

TEST_CASE(
    "compare: --layer picks a Cycles-style layer of multi-layer files, without it the layers are listed")
{
    TempDir dir;
    testkit::ExrLayout layout = float_rgb();
    layout.channel_names = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                            "ViewLayer.Combined.A", "ViewLayer.DiffInd.R",  "ViewLayer.DiffInd.G",
                            "ViewLayer.DiffInd.B",  "ViewLayer.Depth.Z"};
    layout.channel_types.assign(8, "float");
    // Channel c: 0..3 Combined, 4..6 DiffInd, 7 depth.
    auto reference = [](int f, int x, int y, int c) { return reference_value(f, x, y, c % 4); };
    auto test = [&](int f, int x, int y, int c) {
        // DiffInd off by 1/32 where x is even; every other channel far off (and ignored).
        if (c >= 4 && c <= 6)
            return reference(f, x, y, c) + (x % 2 == 0 ? 1.0f / 32.0f : 0.0f);
        return reference(f, x, y, c) + 10.0f;
    };
    testkit::write_sequence(dir.file("ref.%04d.exr"), frames(), layout, reference);
    testkit::write_sequence(dir.file("test.%04d.exr"), frames(), layout, test);
    std::string pair = dir.file("test.####.exr") + " " + dir.file("ref.####.exr");

    auto result =
        run_modestack("compare " + pair + " --layer DiffInd --fail 0.05 --json " + dir.file("c.json"));
    CHECK_MESSAGE(result.exit_code == 1, result.err); // 1/32 is under --fail 0.05, over --warn 1e-6
    CHECK(result.out.find("ViewLayer.DiffInd.R,ViewLayer.DiffInd.G,ViewLayer.DiffInd.B") !=
          std::string::npos);
    auto json = nlohmann::json::parse(read_text(dir.file("c.json")));
    CHECK(json["test_channels"].size() == 3);
    CHECK(json["shot"]["max_absolute_error"] == 1.0 / 32.0);
    CHECK(json["shot"]["percent_warning"] == 50.0);
    double relative = 0;
    for (int f = 1; f <= kFrames; ++f)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 4; c <= 6; ++c) {
                    double d = test(f, x, y, c) - reference(f, x, y, c), r = reference(f, x, y, c);
                    relative += d * d / (r * r + 0.01);
                }
    relative /= double(kFrames) * kWidth * kHeight * 3;
    CHECK(std::abs(double(json["shot"]["relative_mse"]) - relative) < 1e-6 * relative);

    auto same = run_modestack("compare " + dir.file("ref.####.exr") + " " + dir.file("ref.####.exr") +
                              " --layer ViewLayer.DiffInd --layer Depth -q");
    CHECK(same.exit_code == 0);
    // Options before the sequences, as with idiff and oiiotool: each --layer takes one value.
    auto options_first = run_modestack("compare --layer DiffInd --fail 0.05 " + pair + " -q");
    CHECK_MESSAGE(options_first.exit_code == 1, options_first.err);
    auto ambiguous = run_modestack("compare " + pair);
    CHECK(ambiguous.exit_code == 4);
    CHECK(one_line(ambiguous.err));
    CHECK(ambiguous.err.find("ViewLayer.DiffInd") != std::string::npos);
    CHECK(ambiguous.err.find("ViewLayer.Combined") != std::string::npos);
}
