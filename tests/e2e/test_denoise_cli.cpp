// End-to-end: `modestack denoise` on generated multi-layer sequences with a known
// clean signal: it removes noise, keeps every other channel bit-exactly, writes
// sigma and provenance, is deterministic, streams and keeps the shot alike, reads
// and writes the same pixels with either --exr-codec, and refuses bad input with
// one line and nothing written.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::read_text;
using testkit::TempDir;

namespace {
constexpr int kWidth = 40, kHeight = 36, kFrames = 24;

// A rank-2 "lighting" signal: a fixed spatial pattern times a smooth temporal
// weight, plus a second pattern that fades in.
float clean_value(int frame, int x, int y, int c)
{
    float t = static_cast<float>(frame) / kFrames;
    float mode1 = 0.6f + 0.3f * std::sin(0.2f * x + 0.1f * c) * std::cos(0.15f * y);
    float mode2 = 0.4f * (x > kWidth / 2 ? 1.0f : 0.2f) + 0.05f * c;
    return mode1 * (1.0f + 0.2f * t) + mode2 * t * t;
}

float noise(int frame, int x, int y, int c)
{
    std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.15f);
    return normal(generator);
}

testkit::ExrLayout layout()
{
    testkit::ExrLayout result;
    result.width = kWidth;
    result.height = kHeight;
    result.channel_names = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                            "ViewLayer.Combined.A", "ViewLayer.DiffInd.R",  "ViewLayer.DiffInd.G",
                            "ViewLayer.DiffInd.B",  "ViewLayer.Depth.Z"};
    result.channel_types = {"half", "half", "half", "half", "float", "float", "float", "float"};
    result.attributes = {{"renderer", "synthetic"}};
    return result;
}

// Channel c of the layout: DiffInd (4..6) is clean + noise; the rest are other data.
float noisy_value(int frame, int x, int y, int c)
{
    if (c >= 4 && c <= 6)
        return clean_value(frame, x, y, c - 4) + noise(frame, x, y, c - 4);
    return 0.01f * x + 0.02f * y + 0.1f * c + frame;
}

const std::vector<std::string> kDiffInd{"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"};

double mse_against_clean(const std::string& pattern, int frames)
{
    double sum = 0;
    size_t count = 0;
    for (int frame = 1; frame <= frames; ++frame) {
        char name[4096];
        std::snprintf(name, sizeof name, pattern.c_str(), frame);
        std::vector<float> values = testkit::read_channels(name, kDiffInd);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c) {
                    double d = values[(y * kWidth + x) * 3 + c] - clean_value(frame, x, y, c);
                    sum += d * d;
                    ++count;
                }
    }
    return sum / count;
}

std::vector<int> all_frames()
{
    std::vector<int> frames;
    for (int f = 1; f <= kFrames; ++f)
        frames.push_back(f);
    return frames;
}

}  // namespace

// Root mean square of the rebuilt layer's error against the clean signal, and of its sigma.
std::pair<double, double> rms_error_and_sigma(const std::string& pattern, int frames)
{
    double error = 0, sigma = 0;
    size_t count = 0;
    for (int frame = 1; frame <= frames; ++frame) {
        char name[4096];
        std::snprintf(name, sizeof name, pattern.c_str(), frame);
        std::vector<float> values = testkit::read_channels(name, kDiffInd);
        std::vector<float> sigmas = testkit::read_channels(
            name, {"ViewLayer.DiffInd.sigma.R", "ViewLayer.DiffInd.sigma.G", "ViewLayer.DiffInd.sigma.B"});
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c, ++count) {
                    size_t i = (y * kWidth + x) * 3 + c;
                    double d = values[i] - clean_value(frame, x, y, c);
                    error += d * d;
                    sigma += double(sigmas[i]) * sigmas[i];
                }
    }
    return {std::sqrt(error / count), std::sqrt(sigma / count)};
}

TEST_CASE("denoise removes most of the noise, writes sigma, keeps other channels bit-exact and records provenance")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto result = run_modestack("denoise " + dir.file("in.####.exr") + " -o " + dir.file("out/den.####.exr") +
                                " --layer DiffInd --json " + dir.file("summary.json") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    double noisy = mse_against_clean(dir.file("in.%04d.exr"), kFrames);
    double denoised = mse_against_clean(dir.file("out/den.%04d.exr"), kFrames);
    MESSAGE("MSE noisy " << noisy << ", denoised (mode filter) " << denoised);
    // Rank 2 alone keeps about 2/F of the white noise; filtering the modes removes more.
    CHECK(denoised < noisy / 10);

    auto json = nlohmann::json::parse(read_text(dir.file("summary.json")));
    CHECK(json["rank"]["rule"] == "sure");
    CHECK(json["rank"]["n"] >= 2);
    CHECK(json["mode_filter"].size() > 0);
    CHECK(json["frame_count"] == kFrames);
    CHECK(json["solver"] == "gram");
    CHECK(json["singular_values"].size() == static_cast<size_t>(kFrames));
    CHECK(json["outliers"]["non_finite"] == 0);
    // Sigma is an estimate of the error it labels: the same order of magnitude.
    auto [rms_error, rms_sigma] = rms_error_and_sigma(dir.file("out/den.%04d.exr"), kFrames);
    MESSAGE("RMS error " << rms_error << ", RMS sigma " << rms_sigma);
    CHECK(rms_sigma > 0.5 * rms_error);
    CHECK(rms_sigma < 3.0 * rms_error);

    std::string first = dir.file("out/den.0001.exr");
    std::vector<std::string> names = testkit::read_channel_names(first);
    CHECK(names.size() == 11);
    std::vector<std::string> others{"ViewLayer.Combined.R", "ViewLayer.Combined.A", "ViewLayer.Depth.Z"};
    CHECK(testkit::read_channels(first, others) == testkit::read_channels(dir.file("in.0001.exr"), others));
    CHECK(testkit::read_string_attribute(first, "renderer") == "synthetic");
    CHECK(testkit::read_string_attribute(first, "modestack:rank_rule") == "sure");
    CHECK(testkit::read_string_attribute(first, "modestack:command").find("denoise") != std::string::npos);

    // Options before the sequence, as with oiiotool: --layer and the comma lists take one value each,
    // so the sequence stays the positional (here with the default widths and guides spelt out).
    auto options_first = run_modestack("denoise --layer DiffInd --mode-filter-widths 0.75,1,1.5,2,3 "
                                       "--mode-filter-guides auto " +
                                       dir.file("in.####.exr") + " -o " + dir.file("first/den.####.exr") + " -q");
    REQUIRE_MESSAGE(options_first.exit_code == 0, options_first.err);
    CHECK(testkit::read_channels(dir.file("first/den.0001.exr"), kDiffInd) == testkit::read_channels(first, kDiffInd));
}

TEST_CASE("denoise on noise that repeats from frame to frame says so, and its spatial estimators take most "
          "of it out")
{
    // The same noise in every frame, as a renderer with a fixed seed gives it.
    auto repeating_value = [](int frame, int x, int y, int c) {
        if (c >= 4 && c <= 6)
            return clean_value(frame, x, y, c - 4) + noise(1, x, y, c - 4);
        return noisy_value(frame, x, y, c);
    };
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), repeating_value);
    auto result = run_modestack("denoise " + dir.file("in.####.exr") + " -o " + dir.file("out/den.####.exr") +
                                " --layer DiffInd --json " + dir.file("summary.json") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    // One warning line naming the input and the layer, even with -q.
    CHECK(result.err.find("warning: " + dir.file("in.####.exr") +
                          ": the noise of ViewLayer.DiffInd repeats from "
                          "frame to frame") != std::string::npos);
    CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);
    auto json = nlohmann::json::parse(read_text(dir.file("summary.json")));
    const auto& repeating = json["layers"][0]["repeating_noise"];
    CHECK(repeating["repeats"] == true);
    CHECK(repeating["share"].get<double>() > 0.9);
    CHECK(repeating["whiteness"].get<double>() > 0.8);
    CHECK(repeating["frames_read"] == 9);
    CHECK(repeating["counted"] == true);
    // The temporal rebuild alone keeps it; the choice, counting it, removes most of it.
    auto rebuild =
        run_modestack("denoise " + dir.file("in.####.exr") + " -o " + dir.file("rebuild/den.####.exr") +
                      " --layer DiffInd --estimators rebuild -q");
    REQUIRE_MESSAGE(rebuild.exit_code == 0, rebuild.err);
    CHECK(rebuild.err.find("(--estimators without spatial leaves it in)") != std::string::npos);
    const double noisy = mse_against_clean(dir.file("in.%04d.exr"), kFrames);
    const double kept = mse_against_clean(dir.file("rebuild/den.%04d.exr"), kFrames);
    const double chosen = mse_against_clean(dir.file("out/den.%04d.exr"), kFrames);
    MESSAGE("MSE noisy " << noisy << ", rebuild alone " << kept << ", default " << chosen);
    CHECK(kept > 0.5 * noisy);
    CHECK(chosen < 0.35 * noisy);
    // And sigma says about how large the error is (the rebuild's sigma alone does not see it).
    auto [rms_error, rms_sigma] = rms_error_and_sigma(dir.file("out/den.%04d.exr"), kFrames);
    MESSAGE("RMS error " << rms_error << ", RMS sigma " << rms_sigma);
    CHECK(rms_sigma > 0.5 * rms_error);
    CHECK(rms_sigma < 2.0 * rms_error);

    // Noise new in every frame: no warning, nothing counted, the bits of a run that never looked.
    TempDir fresh;
    testkit::write_sequence(fresh.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto plain =
        run_modestack("denoise " + fresh.file("in.####.exr") + " -o " + fresh.file("out/den.####.exr") +
                      " --layer DiffInd --json " + fresh.file("summary.json") + " -q");
    REQUIRE_MESSAGE(plain.exit_code == 0, plain.err);
    CHECK(plain.err.find("repeats") == std::string::npos);
    auto plain_json = nlohmann::json::parse(read_text(fresh.file("summary.json")));
    CHECK(plain_json["layers"][0]["repeating_noise"]["repeats"] == false);
    CHECK(plain_json["layers"][0]["repeating_noise"]["share"].get<double>() < 0.3);
}

TEST_CASE("denoise --no-mode-filter: press picks the true rank 2 and sigma matches a rank-2 rebuild's noise")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto result = run_modestack("denoise " + dir.file("in.####.exr") + " -o " + dir.file("out/den.####.exr") +
                                " --layer DiffInd --no-mode-filter --json " + dir.file("summary.json") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    CHECK(mse_against_clean(dir.file("out/den.%04d.exr"), kFrames) < mse_against_clean(dir.file("in.%04d.exr"), kFrames) / 5);
    auto json = nlohmann::json::parse(read_text(dir.file("summary.json")));
    CHECK(json["rank"]["n"] == 2);
    CHECK(json["rank"]["rule"] == "press");
    // Noise 0.15 per frame, rank 2 of 24 frames: the rebuilt value's error is about 0.15*sqrt(2/24) = 0.043.
    auto [rms_error, rms_sigma] = rms_error_and_sigma(dir.file("out/den.%04d.exr"), kFrames);
    MESSAGE("RMS error " << rms_error << ", RMS sigma " << rms_sigma);
    CHECK(rms_error == doctest::Approx(0.043).epsilon(0.25));
    CHECK(rms_sigma == doctest::Approx(rms_error).epsilon(0.35));
}

TEST_CASE("denoise output pixels are identical for --threads 1 and 2 and for streamed and kept shots")
{
    TempDir dir;
    // 400 rows, so that a budget can stream the shot but not keep it (see below).
    testkit::ExrLayout tall = layout();
    tall.height = 400;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), tall, noisy_value);
    std::string input = dir.file("in.####.exr") + " --layer DiffInd -q ";
    REQUIRE(run_modestack("denoise " + input + "--threads 1 -o " + dir.file("a/d.####.exr") + " --json " +
                          dir.file("a.json"))
                .exit_code == 0);
    REQUIRE(run_modestack("denoise " + input + "--threads 2 -o " + dir.file("b/d.####.exr")).exit_code == 0);
    // Streaming: the mode filter's halo (11 rows each side) makes a 16-row band taller than
    // the budget below allows, so first compare streamed and kept without it; with it, the
    // passes with a halo walk shorter bands (checked after). Per row of all 24 frames, 40 px: 11.5 KB of
    // selected input, 45.6 KB of pass 2's buffers (3 per frame + 23 modes) and 23 KB of native rows (24-byte
    // pixels) the source keeps for the pass-through copy; the estimator choice (the default) adds the rows of
    // its windows around each band. 4.4 MB hold a streamed band with its halo (and the
    // outlier marks, 48 KB), but not the kept shot (4.6 MB of input) with a pass-2 window.
    // --max-memory bounds the whole process: the kept run's JSON says what the program and
    // its open files hold, and the streamed run gets that plus 4.4 MB.
    REQUIRE(run_modestack("denoise " + input + "--no-mode-filter -o " + dir.file("c/d.####.exr") + " --json " +
                          dir.file("c.json"))
                .exit_code == 0);
    const auto held = nlohmann::json::parse(read_text(dir.file("c.json")))["memory_held_bytes"].get<std::int64_t>();
    CHECK(held > 0);
    auto streamed = run_modestack("denoise " + input + "--no-mode-filter --max-memory " +
                                  std::to_string(held + 4'400'000) + " --json " + dir.file("d.json") +
                                  " -o " + dir.file("d/d.####.exr"));
    REQUIRE_MESSAGE(streamed.exit_code == 0, streamed.err);
    auto json = nlohmann::json::parse(read_text(dir.file("d.json")));
    CHECK(json["in_memory"] == false);
    CHECK(json["passes"] == 2);
    CHECK(json["band_rows"] < 400);
    // With the mode filter and the choice (the default), 3.7 MB fit no 16-row band
    // with its halo: the survey and pass 2 walk shorter bands, and the output is the
    // kept run's. (Measured: 1-row bands fit from 3.0 MB, 16-row ones from 4.9 MB;
    // the program's own resident size varies by some 100 KB from run to run.)
    const auto default_held =
        nlohmann::json::parse(read_text(dir.file("a.json")))["memory_held_bytes"].get<std::int64_t>();
    auto short_bands =
        run_modestack("denoise " + input + "--max-memory " + std::to_string(default_held + 3'700'000) +
                      " --json " + dir.file("e.json") + " -o " + dir.file("e/d.####.exr"));
    REQUIRE_MESSAGE(short_bands.exit_code == 0, short_bands.err);
    json = nlohmann::json::parse(read_text(dir.file("e.json")));
    CHECK(json["in_memory"] == false);
    CHECK(json["band_rows"] == 16);
    CHECK(json["halo_band_rows"] < 16);
    for (int frame : {1, 13, 24}) {
        char name[64];
        std::snprintf(name, sizeof name, "/d.%04d.exr", frame);
        CHECK(testkit::read_native(dir.path() + "/a" + name) == testkit::read_native(dir.path() + "/b" + name));
        CHECK(testkit::read_native(dir.path() + "/c" + name) == testkit::read_native(dir.path() + "/d" + name));
        CHECK(testkit::read_native(dir.path() + "/a" + name) ==
              testkit::read_native(dir.path() + "/e" + name));
        // The pass-through channels come from the rows the source decoded: still the input's.
        std::vector<std::string> others{"ViewLayer.Combined.R", "ViewLayer.Combined.A", "ViewLayer.Depth.Z"};
        char input_name[64];
        std::snprintf(input_name, sizeof input_name, "/in.%04d.exr", frame);
        CHECK(testkit::read_channels(dir.path() + "/d" + name, others) ==
              testkit::read_channels(dir.path() + input_name, others));
    }
}

TEST_CASE("denoise and compare --exr-codec openimageio: the same pixels as libdeflate's, other compressed bytes")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    std::string input = dir.file("in.####.exr") + " --layer DiffInd -q ";
    REQUIRE(run_modestack("denoise " + input + "-o " + dir.file("a/d.####.exr")).exit_code == 0);
    REQUIRE(run_modestack("denoise " + input + "--exr-codec openimageio -o " + dir.file("b/d.####.exr")).exit_code ==
            0);
    for (int frame : {1, 24}) {
        char name[64];
        std::snprintf(name, sizeof name, "/d.%04d.exr", frame);
        CHECK(testkit::read_native(dir.path() + "/a" + name) == testkit::read_native(dir.path() + "/b" + name));
        CHECK(read_text(dir.path() + "/a" + name) != read_text(dir.path() + "/b" + name));
    }
    const std::string sequences = dir.file("a/d.####.exr") + " " + dir.file("b/d.####.exr") + " --layer DiffInd ";
    auto ours = run_modestack("compare " + sequences);
    auto theirs = run_modestack("compare --exr-codec openimageio " + sequences);
    CHECK(ours.exit_code == 0);
    CHECK(theirs.exit_code == 0);
    CHECK(ours.out == theirs.out);
    auto unknown = run_modestack("denoise " + input + "--exr-codec zlib -o " + dir.file("c/d.####.exr"));
    CHECK(unknown.exit_code == 2);
    CHECK(unknown.err.find("--exr-codec: 'zlib' is not one of libdeflate, openimageio") != std::string::npos);
}

TEST_CASE("denoise --method rsvd agrees with gram, --rank N is honoured, --save-modes writes modes and weights")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    std::string input = "denoise " + dir.file("in.####.exr") + " --layer DiffInd -q --rank 2 ";
    // The randomized SVD fits even frame noise: the Gram route agrees with it so.
    REQUIRE(
        run_modestack(input + "--method gram --frame-noise even -o " + dir.file("g/d.####.exr")).exit_code ==
        0);
    REQUIRE(run_modestack(input + "--method rsvd --save-modes " + dir.file("modes") + " -o " + dir.file("r/d.####.exr"))
                .exit_code == 0);
    std::vector<float> gram = testkit::read_channels(dir.file("g/d.0007.exr"), kDiffInd);
    std::vector<float> rsvd = testkit::read_channels(dir.file("r/d.0007.exr"), kDiffInd);
    double largest = 0;
    for (size_t i = 0; i < gram.size(); ++i)
        largest = std::max(largest, static_cast<double>(std::fabs(gram[i] - rsvd[i])));
    CHECK(largest < 1e-4);
    CHECK(testkit::read_string_attribute(dir.file("r/d.0007.exr"), "modestack:solver") == "rsvd");
    CHECK(testkit::list_directory(dir.file("modes")) ==
          std::vector<std::string>{"mode.01.exr", "mode.02.exr", "temporal_modes.csv", "temporal_modes.json"});
    std::string csv = read_text(dir.file("modes/temporal_modes.csv"));
    CHECK(csv.rfind("frame,mode1,mode2\n", 0) == 0);
    CHECK(std::count(csv.begin(), csv.end(), '\n') == kFrames + 1);
}

TEST_CASE("denoise counts and replaces NaN/Inf, and --skip-existing leaves finished frames alone")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), [](int frame, int x, int y, int c) {
        if (frame == 5 && x == 3 && y == 4 && c == 4)
            return std::nanf("");
        if (frame == 6 && x == 1 && y == 1 && c == 5)
            return INFINITY;
        return noisy_value(frame, x, y, c);
    });
    auto result = run_modestack("denoise " + dir.file("in.####.exr") + " --layer DiffInd -o " +
                                dir.file("out/d.####.exr") + " --json " + dir.file("s.json"));
    REQUIRE(result.exit_code == 0);
    CHECK(result.err.find("2 NaN/Inf values") != std::string::npos);
    CHECK(nlohmann::json::parse(read_text(dir.file("s.json")))["outliers"]["non_finite"] == 2);
    for (float value : testkit::read_channels(dir.file("out/d.0005.exr"), kDiffInd))
        CHECK(std::isfinite(value));

    std::remove(dir.file("out/d.0003.exr").c_str());
    auto second = run_modestack("denoise " + dir.file("in.####.exr") + " --layer DiffInd --skip-existing -q -o " +
                                dir.file("out/d.####.exr") + " --json " + dir.file("s2.json"));
    REQUIRE(second.exit_code == 0);
    CHECK(nlohmann::json::parse(read_text(dir.file("s2.json")))["frames_written"] == 1);
    CHECK(testkit::list_directory(dir.file("out")).size() == kFrames);
}

TEST_CASE("denoise bad input: one line naming the problem, documented exit code, nothing written")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    testkit::write_sequence(dir.file("two.%04d.exr"), {1, 2}, layout(), noisy_value);
    testkit::write_sequence(dir.file("mix.%04d.exr"), {1, 2, 3}, layout(), noisy_value);
    testkit::ExrLayout smaller = layout();
    smaller.height = kHeight - 1;
    testkit::write_sequence(dir.file("mix.%04d.exr"), {4}, smaller, noisy_value);
    testkit::write_sequence(dir.file("trunc.%04d.exr"), {1, 2, 3}, layout(), noisy_value);
    {
        std::string bytes = read_text(dir.file("trunc.0002.exr"));
        std::ofstream(dir.file("trunc.0002.exr"), std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
    }
    std::string out = " -q -o " + dir.file("out/d.####.exr");
    struct Case {
        std::string arguments;
        int exit_code;
        std::string message;
    };
    std::vector<Case> cases{
        {dir.file("two.####.exr") + " --layer DiffInd" + out, 1, "two.####.exr: denoising needs at least 3 frames"},
        {dir.file("in.####.exr") + " --layer DiffInd --rank 24" + out, 1, "--rank 24 needs more than 24 frames"},
        {dir.file("in.####.exr") + " --layer DiffInd --rank 0" + out, 2, "--rank 0"},
        {dir.file("in.####.exr") + " --layer GlossInd" + out, 1, "in.0001.exr: layer 'GlossInd' not found"},
        {dir.file("in.####.exr") + out, 1, "several RGB layers; choose with --layer"},
        {dir.file("mix.####.exr") + " --layer DiffInd" + out, 1, "mix.0004.exr: data window 40x35 differs"},
        {dir.file("trunc.####.exr") + " --layer DiffInd" + out, 1, "trunc.0002.exr: cannot read rows"},
        {dir.file("in.####.exr") + " --layer DiffInd -q -o " + dir.file("in.####.exr"), 2, "is also an input"},
        {dir.file("in.####.exr") + " --layer DiffInd -q -o " + dir.file("in.0001.exr") + "/d.####.exr", 1,
         "output directory"},
        {dir.file("in.####.exr") + " --layer DiffInd --max-memory lots" + out, 2, "--max-memory 'lots'"},
        {dir.file("in.####.exr") + " --layer DiffInd --method svd" + out, 2, "--method 'svd'"},
        {dir.file("in.####.exr") + " --layer DiffInd --rank-rule magic" + out, 2, "magic"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack("denoise " + c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK(result.err.find('\n') == result.err.size() - 1);
        CHECK_MESSAGE(result.err.find(c.message) != std::string::npos, result.err);
        CHECK_FALSE(std::ifstream(dir.file("out/d.0001.exr")).good());
        if (std::ifstream(dir.file("out")).good())
            CHECK(testkit::list_directory(dir.file("out")).empty());
    }
}
