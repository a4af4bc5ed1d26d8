// End-to-end: the method options of `modestack denoise` (issue 8) through the
// real binary on a tiny sequence: --transform round-trips a static shot and is
// recorded, --non-negative leaves no negative value and counts its changes,
// --shrink optimal reports its factors, --segments splits by a list and finds a
// planted cut, --weight-smoothing lowers flicker and keeps a lighting step,
// --whiten finds a Cycles-style variance layer and keeps a quiet region's mode;
// --mode-filter-guides finds Cycles-style features and keeps an albedo edge;
// --rank-map writes its map and summary; --estimators takes a sweeping
// shadow from the input's neighbourhood and reports its choice per frame;
// bad values and combinations exit 2 with one line naming the
// option and write nothing.
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
using testkit::TempDir;

namespace {
constexpr int kWidth = 24, kHeight = 20, kFrames = 12, kCut = 7; // frame numbers 1..12; lighting changes at 7

float clean_value(int frame, int x, int y, int c)
{
    const float t = static_cast<float>(frame) / kFrames;
    const float base = (x < kWidth / 3 ? 0.0f : 0.5f + 0.2f * std::sin(0.3f * y + c)); // a black third
    return base * (1.0f + 0.3f * t);
}

float noise(int frame, int x, int y, int c)
{
    std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.1f);
    return normal(generator);
}

float noisy_value(int frame, int x, int y, int c)
{
    return clean_value(frame, x, y, c) + noise(frame, x, y, c);
}

// From frame kCut on a second light brightens the bottom half.
float cut_value(int frame, int x, int y, int c)
{
    return noisy_value(frame, x, y, c) + (frame >= kCut && y >= kHeight / 2 ? 1.5f : 0.0f);
}

testkit::ExrLayout layout()
{
    testkit::ExrLayout result;
    result.width = kWidth;
    result.height = kHeight;
    result.channel_types = {"float", "float", "float"};
    return result;
}

std::vector<int> all_frames()
{
    std::vector<int> frames;
    for (int f = 1; f <= kFrames; ++f)
        frames.push_back(f);
    return frames;
}

// Σ over every frame of `pattern` (printf form) of the squared error of the
// Cycles-style ViewLayer.DiffInd channels against truth(frame, x, y, c), in
// columns [x0, x1); `count` receives the number of samples.
template <typename Truth>
double diffind_squared_error(const std::string& pattern, int x0, int x1, Truth truth, int* count = nullptr)
{
    double sum = 0;
    int samples = 0;
    for (int frame = 1; frame <= kFrames; ++frame) {
        char name[4096];
        std::snprintf(name, sizeof name, pattern.c_str(), frame);
        std::vector<float> values =
            testkit::read_channels(name, {"ViewLayer.DiffInd.R", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.B"});
        for (int y = 0; y < kHeight; ++y)
            for (int x = x0; x < x1; ++x)
                for (int c = 0; c < 3; ++c, ++samples) {
                    const double error = values[(size_t(y) * kWidth + x) * 3 + c] - truth(frame, x, y, c);
                    sum += error * error;
                }
    }
    if (count)
        *count = samples;
    return sum;
}

nlohmann::json load_json(const std::string& path)
{
    std::ifstream file(path);
    std::stringstream text;
    text << file.rdbuf();
    return nlohmann::json::parse(text.str());
}

std::vector<float> all_values(const std::string& printf_pattern)
{
    std::vector<float> values;
    for (int frame = 1; frame <= kFrames; ++frame) {
        char name[4096];
        std::snprintf(name, sizeof name, printf_pattern.c_str(), frame);
        std::vector<float> part = testkit::read_channels(name, {"R", "G", "B"});
        values.insert(values.end(), part.begin(), part.end());
    }
    return values;
}
// The mean squared error of every frame of `printf_pattern` (R, G, B) against truth(frame, x, y, c).
template <typename Truth> double shot_mse(const std::string& printf_pattern, Truth truth)
{
    std::vector<float> values = all_values(printf_pattern);
    double sum = 0;
    size_t i = 0;
    for (int frame = 1; frame <= kFrames; ++frame)
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c, ++i)
                    sum += (values[i] - truth(frame, x, y, c)) * (values[i] - truth(frame, x, y, c));
    return sum / static_cast<double>(values.size());
}
} // namespace

TEST_CASE("denoise --transform: a static shot comes back to float precision, the map is recorded")
{
    TempDir dir;
    testkit::write_sequence(dir.file("still.%04d.exr"), all_frames(), layout(),
                            [](int, int x, int y, int c) { return 0.05f + clean_value(1, x, y, c); });
    for (std::string transform : {"log", "pow:2.2"}) {
        CAPTURE(transform);
        std::string out = dir.file(transform.substr(0, 3) + "/d.####.exr"),
                    json = dir.file(transform + ".json");
        auto result = run_modestack("denoise " + dir.file("still.####.exr") +
                                    " -q --no-mode-filter --rank 1 --transform " + transform + " --json " +
                                    json + " -o " + out);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
        std::vector<float> input = all_values(dir.file("still.%04d.exr"));
        std::vector<float> output = all_values(dir.file(transform.substr(0, 3) + "/d.%04d.exr"));
        double worst = 0;
        for (size_t i = 0; i < input.size(); ++i)
            worst = std::max(worst, static_cast<double>(std::fabs(output[i] - input[i])));
        CHECK(worst < 1e-5);
        auto summary = load_json(json);
        CHECK(summary["method"]["transform"]["name"] == transform);
        if (transform == "log")
            CHECK(summary["method"]["transform"]["epsilon"].get<double>() > 0);
        CHECK(testkit::read_string_attribute(dir.file(transform.substr(0, 3) + "/d.0001.exr"),
                                             "modestack:transform") == transform);
    }
}

TEST_CASE("denoise --non-negative: no negative value, the changes are counted")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    // The rebuild alone: the count is of the rebuild's negatives.
    std::string input =
        "denoise " + dir.file("in.####.exr") + " -q --no-mode-filter --rank 1 --estimators rebuild ";
    REQUIRE(run_modestack(input + "-o " + dir.file("off/d.####.exr")).exit_code == 0);
    std::vector<float> off = all_values(dir.file("off/d.%04d.exr"));
    const auto negatives = std::count_if(off.begin(), off.end(), [](float v) { return v < 0; });
    REQUIRE(negatives > 0);
    for (std::string mode : {"clamp", "keep-sum"}) {
        CAPTURE(mode);
        auto result = run_modestack(input + "--non-negative --non-negative-mode " + mode + " --json " +
                                    dir.file(mode + ".json") + " -o " + dir.file(mode + "/d.####.exr"));
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
        std::vector<float> on = all_values(dir.file(mode + "/d.%04d.exr"));
        CHECK(*std::min_element(on.begin(), on.end()) >= 0.0f);
        auto summary = load_json(dir.file(mode + ".json"));
        CHECK(summary["method"]["non_negative"]["mode"] == mode);
        CHECK(summary["method"]["non_negative"]["clamped_values"] == negatives);
    }
}

TEST_CASE("denoise --shrink optimal: factors in [0, 1] per kept mode")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto result = run_modestack("denoise " + dir.file("in.####.exr") +
                                " -q --no-mode-filter --rank 3 --shrink optimal "
                                "--json " +
                                dir.file("s.json") + " -o " + dir.file("out/d.####.exr"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    auto shrink = load_json(dir.file("s.json"))["method"]["shrink"];
    CHECK(shrink["method"] == "optimal");
    REQUIRE(shrink["factors"].size() == 3);
    CHECK(shrink["factors"][0].get<double>() > 0.9);
    for (const auto& factor : shrink["factors"])
        CHECK((factor.get<double>() >= 0 && factor.get<double>() <= 1));
}

TEST_CASE("denoise --segments: a list is honoured and auto finds the planted cut")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), cut_value);
    std::string input = "denoise " + dir.file("in.####.exr") + " -q ";
    auto listed = run_modestack(input + "--segments 1-6,7-12 --json " + dir.file("l.json") + " -o " +
                                dir.file("l/d.####.exr"));
    REQUIRE_MESSAGE(listed.exit_code == 0, listed.err);
    auto segments = load_json(dir.file("l.json"))["method"]["segments"];
    CHECK(segments["mode"] == "list");
    REQUIRE(segments["parts"].size() == 2);
    CHECK(segments["parts"][1]["frames"] == "7-12");
    CHECK(testkit::list_directory(dir.file("l")).size() == kFrames);

    auto automatic = run_modestack(input + "--segments auto --json " + dir.file("a.json") + " -o " +
                                   dir.file("a/d.####.exr"));
    REQUIRE_MESSAGE(automatic.exit_code == 0, automatic.err);
    auto found = load_json(dir.file("a.json"));
    CHECK(found["method"]["segments"]["cuts"] == std::vector<int>{kCut});
    CHECK(found["frame_count"] == kFrames);
    // Same parts, same result.
    CHECK(all_values(dir.file("a/d.%04d.exr")) == all_values(dir.file("l/d.%04d.exr")));
}

TEST_CASE("denoise --train-frames: modes from every 3rd frame, every frame written, close to the full run")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    std::string input = "denoise " + dir.file("in.####.exr") + " -q --no-mode-filter --rank 2 ";
    REQUIRE(run_modestack(input + "-o " + dir.file("all/d.####.exr")).exit_code == 0);
    auto result = run_modestack(input + "--train-frames 1-12x3 --json " + dir.file("t.json") + " -o " +
                                dir.file("t/d.####.exr"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    auto summary = load_json(dir.file("t.json"));
    CHECK(summary["method"]["train_frames"]["frames"] == 4);
    CHECK(summary["singular_values"].size() == 4);
    CHECK(summary["temporal_modes"][0].size() == kFrames);
    // Against the clean signal: the rebuild keeps about N/F_T = 2/4 of the noise
    // variance (0.1²) with modes from 4 frames, N/F = 2/12 with all of them.
    auto error = [&](const std::string& pattern) { return shot_mse(pattern, clean_value); };
    const double all_error = error(dir.file("all/d.%04d.exr")),
                 trained_error = error(dir.file("t/d.%04d.exr"));
    MESSAGE("MSE all frames " << all_error << ", modes from 4 of 12 frames " << trained_error);
    CHECK(all_error < trained_error);
    CHECK(trained_error < 0.1 * 0.1 * 0.75);
}

TEST_CASE("denoise --weight-smoothing (default): less flicker against the truth, the lighting step kept, per part")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), cut_value);
    std::string input = "denoise " + dir.file("in.####.exr") + " -q --no-mode-filter --rank 4 ";
    auto off_run = run_modestack(input + "--no-weight-smoothing --json " + dir.file("off.json") + " -o " +
                                 dir.file("off/d.####.exr"));
    REQUIRE_MESSAGE(off_run.exit_code == 0, off_run.err);
    CHECK(load_json(dir.file("off.json"))["method"]["weight_smoothing"]["enabled"] == false);
    auto result = run_modestack(input + "--json " + dir.file("w.json") + " -o " + dir.file("on/d.####.exr"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    auto smoothing = load_json(dir.file("w.json"))["method"]["weight_smoothing"];
    CHECK(smoothing["enabled"] == true);
    REQUIRE(smoothing["modes"].size() == 4);
    for (const auto& mode : smoothing["modes"])
        CHECK(mode["sure_gain"].get<double>() >= 0);
    // Flicker against the clean shot, and the step of the bottom half at kCut.
    auto truth = [](int frame, int x, int y, int c) {
        return clean_value(frame, x, y, c) + (frame >= kCut && y >= kHeight / 2 ? 1.5f : 0.0f);
    };
    auto measure = [&](const std::string& pattern, double& flicker, double& step) {
        std::vector<float> values = all_values(pattern);
        const size_t frame_samples = size_t(kWidth) * kHeight * 3;
        flicker = 0, step = 0;
        for (int frame = 2; frame <= kFrames; ++frame)
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int c = 0; c < 3; ++c) {
                        const size_t i = (size_t(frame - 1) * kHeight * kWidth + size_t(y) * kWidth + x) * 3 + c;
                        const double change = values[i] - values[i - frame_samples];
                        const double error = change - (truth(frame, x, y, c) - truth(frame - 1, x, y, c));
                        flicker += error * error;
                        if (frame == kCut && y >= kHeight / 2)
                            step += change / (kHeight / 2 * kWidth * 3);
                    }
        flicker /= (kFrames - 1) * frame_samples;
    };
    double off_flicker = 0, off_step = 0, on_flicker = 0, on_step = 0;
    measure(dir.file("off/d.%04d.exr"), off_flicker, off_step);
    measure(dir.file("on/d.%04d.exr"), on_flicker, on_step);
    MESSAGE("flicker off " << off_flicker << ", on " << on_flicker << "; step off " << off_step << ", on "
                           << on_step);
    CHECK(on_flicker < off_flicker);
    CHECK(on_step == doctest::Approx(1.5).epsilon(0.05));
    // With --segments each part smooths its own weights.
    auto parts = run_modestack("denoise " + dir.file("in.####.exr") +
                               " -q --no-mode-filter --rank 2 --segments 1-6,7-12 --json " +
                               dir.file("p.json") + " -o " + dir.file("p/d.####.exr"));
    REQUIRE_MESSAGE(parts.exit_code == 0, parts.err);
    auto segments = load_json(dir.file("p.json"))["method"]["segments"]["parts"];
    REQUIRE(segments.size() == 2);
    CHECK(segments[1]["weight_smoothing_widths"].size() == 2);
}

TEST_CASE("denoise --whiten: found by name in Cycles-style layers, keeps the quiet half's weak mode")
{
    // Left half: bright and noisy (0.5); right half: dim, quiet (0.02) and a weak
    // mode of its own that the left half's noise modes hide from hard truncation.
    constexpr float noisy_deviation = 0.5f, quiet_deviation = 0.02f;
    auto truth = [](int frame, int x, int y, int c) {
        const float time = static_cast<float>(frame) / kFrames;
        if (x < kWidth / 2)
            return 4.0f + 2.0f * std::sin(0.2f * y + c) * std::cos(3.0f * time);
        return 0.3f + 0.1f * std::cos(0.4f * x + 0.3f * y + c) * std::sin(5.0f * time + 1.0f);
    };
    auto deviation = [&](int x) { return x < kWidth / 2 ? noisy_deviation : quiet_deviation; };
    testkit::ExrLayout variance_layout = layout();
    variance_layout.channel_names = {"ViewLayer.DiffInd.B",    "ViewLayer.DiffInd.G",    "ViewLayer.DiffInd.R",
                                     "ViewLayer.DiffIndVar.B", "ViewLayer.DiffIndVar.G", "ViewLayer.DiffIndVar.R"};
    variance_layout.channel_types.assign(6, "float");
    TempDir dir;
    testkit::write_sequence(dir.file("v.%04d.exr"), all_frames(), variance_layout, [&](int frame, int x, int y, int c) {
        if (c >= 3)
            return deviation(x) * deviation(x);
        return truth(frame, x, y, 2 - c) + deviation(x) / 0.1f * noise(frame, x, y, c);
    });
    std::string input = "denoise " + dir.file("v.####.exr") + " -q --layer DiffInd --no-mode-filter --rank 3 ";
    auto off = run_modestack(input + "--whiten off --json " + dir.file("off.json") + " -o " + dir.file("off/d.####.exr"));
    REQUIRE_MESSAGE(off.exit_code == 0, off.err);
    auto on = run_modestack(input + "--whiten auto --json " + dir.file("on.json") + " -o " + dir.file("on/d.####.exr"));
    REQUIRE_MESSAGE(on.exit_code == 0, on.err);
    auto whiten = load_json(dir.file("on.json"))["method"]["whiten"];
    CHECK(whiten["mode"] == "on");
    CHECK(whiten["reason"] == "variance layer");
    CHECK(whiten["weight_max"].get<double>() / whiten["weight_min"].get<double>() ==
          doctest::Approx(noisy_deviation / quiet_deviation).epsilon(1e-4));
    CHECK(load_json(dir.file("off.json"))["method"]["whiten"]["mode"] == "off");
    auto quiet_error = [&](const std::string& pattern) {
        int count = 0;
        const double sum = diffind_squared_error(pattern, kWidth / 2 + 1, kWidth, truth, &count);
        return sum / count;
    };
    const double off_error = quiet_error(dir.file("off/d.%04d.exr")), on_error = quiet_error(dir.file("on/d.%04d.exr"));
    MESSAGE("quiet half MSE: plain " << off_error << ", whitened " << on_error << " (noise variance "
                                     << quiet_deviation * quiet_deviation << ")");
    CHECK(on_error < off_error / 2);

    // No variance layer: auto stays off and says why; on is an input error.
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto plain = run_modestack("denoise " + dir.file("in.####.exr") + " -q --whiten auto --json " +
                               dir.file("p.json") + " -o " + dir.file("p/d.####.exr"));
    REQUIRE_MESSAGE(plain.exit_code == 0, plain.err);
    CHECK(load_json(dir.file("p.json"))["method"]["whiten"]["reason"] == "no variance layer");
    auto refused = run_modestack("denoise " + dir.file("in.####.exr") + " -q --whiten on -o " +
                                 dir.file("r/d.####.exr"));
    CHECK(refused.exit_code == 1);
    CHECK(refused.err.find("--whiten on needs a variance layer") != std::string::npos);
    CHECK_FALSE(std::ifstream(dir.file("r/d.0001.exr")).good());
}

TEST_CASE("denoise --mode-filter-guides: Cycles-style albedo and normal found by name, an albedo edge kept sharper")
{
    // A reflectance step at x = kWidth / 2 in the light, with the same step in
    // DiffCol; the normal is the same everywhere (no edge: dropped).
    auto truth = [](int frame, int x, int y, int) {
        const float time = static_cast<float>(frame) / kFrames;
        return (x < kWidth / 2 ? 0.2f : 1.0f) * (1.0f + 0.4f * std::sin(0.3f * y) * std::cos(3.0f * time));
    };
    testkit::ExrLayout guides_layout = layout();
    guides_layout.channel_names = {"ViewLayer.DiffCol.B", "ViewLayer.DiffCol.G", "ViewLayer.DiffCol.R",
                                   "ViewLayer.DiffInd.B", "ViewLayer.DiffInd.G", "ViewLayer.DiffInd.R",
                                   "ViewLayer.Normal.X",  "ViewLayer.Normal.Y",  "ViewLayer.Normal.Z"};
    guides_layout.channel_types.assign(9, "float");
    TempDir dir;
    testkit::write_sequence(dir.file("g.%04d.exr"), all_frames(), guides_layout, [&](int frame, int x, int y, int c) {
        if (c < 3)
            return x < kWidth / 2 ? 0.2f : 1.0f;
        if (c >= 6)
            return c == 7 ? 1.0f : 0.0f;
        return truth(frame, x, y, c) + 2.0f * noise(frame, x, y, c);
    });
    const std::string input = "denoise " + dir.file("g.####.exr") + " -q --layer DiffInd ";
    auto guided = run_modestack(input + "--json " + dir.file("on.json") + " -o " + dir.file("on/d.####.exr"));
    REQUIRE_MESSAGE(guided.exit_code == 0, guided.err);
    auto plain = run_modestack(input + "--mode-filter-guides none --json " + dir.file("off.json") + " -o " +
                               dir.file("off/d.####.exr"));
    REQUIRE_MESSAGE(plain.exit_code == 0, plain.err);
    auto on = load_json(dir.file("on.json"))["mode_filter"];
    CHECK(on["feature_guides"] == nlohmann::json::array({"albedo"}));
    CHECK(on["feature_frames"].size() == 4);
    CHECK(load_json(dir.file("off.json"))["mode_filter"]["feature_guides"].empty());
    auto edge_error = [&](const std::string& pattern) {
        return diffind_squared_error(pattern, kWidth / 2 - 2, kWidth / 2 + 2, truth);
    };
    const double with_guides = edge_error(dir.file("on/d.%04d.exr")), without = edge_error(dir.file("off/d.%04d.exr"));
    MESSAGE("squared error next to the edge: without guides " << without << ", with " << with_guides);
    CHECK(with_guides < 0.7 * without);

    // --max-memory counts the guide layers' files (each opened again as its own
    // sequence): the inputs and the two guides' files here.
    const std::pair<std::string, int> runs[] = {{"", 3 * kFrames}, {"--mode-filter-guides none ", kFrames}};
    for (const auto& [guides, files] : runs) {
        auto small = run_modestack(input + guides + "--max-memory 1M -o " + dir.file("small/d.####.exr"));
        CHECK(small.exit_code == 2);
        CHECK_MESSAGE(small.err.find("its " + std::to_string(files) + " input files") != std::string::npos,
                      small.err);
    }
    CHECK(load_json(dir.file("on.json"))["memory_held_bytes"].get<std::int64_t>() >
          load_json(dir.file("off.json"))["memory_held_bytes"].get<std::int64_t>());
}

TEST_CASE("denoise --rank-map: one 'rank' channel, never below N, summarised in the JSON")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    auto result = run_modestack("denoise " + dir.file("in.####.exr") + " -q --rank 2 --rank-map " +
                                dir.file("rank.exr") + " --json " + dir.file("s.json") + " -o " +
                                dir.file("out/d.####.exr"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    std::vector<float> ranks = testkit::read_channels(dir.file("rank.exr"), {"rank"});
    REQUIRE(ranks.size() == std::size_t(kWidth) * kHeight);
    // The default estimators (auto) are the rebuild alone with a rank map: its map is of the rebuild.
    CHECK(load_json(dir.file("s.json"))["method"]["estimators"]["set"] == nlohmann::json::array({"rebuild"}));
    auto summary = load_json(dir.file("s.json"))["rank_map"];
    const int largest = summary["largest_rank"].get<int>();
    CHECK(largest >= 2);
    double sum = 0;
    for (float kept_modes : ranks) {
        CHECK(kept_modes >= 2.0f);
        CHECK(kept_modes <= static_cast<float>(largest));
        sum += kept_modes;
    }
    CHECK(summary["mean"].get<double>() == doctest::Approx(sum / ranks.size()).epsilon(1e-5));
    CHECK(summary["file"] == dir.file("rank.exr"));
    std::int64_t counted = 0;
    for (const auto& count : summary["pixels_per_whole_rank"])
        counted += count.get<std::int64_t>();
    CHECK(counted == std::int64_t(kWidth) * kHeight);
    for (const std::string& name : testkit::list_directory(dir.path()))  // nothing left under a temporary name
        CHECK(name.find("modestack-tmp") == std::string::npos);
}

TEST_CASE("denoise --estimators: a shadow that sweeps comes out better than the rebuild alone, the choice "
          "per frame "
          "in the JSON")
{
    // A lit wall with a dark bar's sharp shadow moving 2 px a frame: no few modes follow it.
    auto truth = [](int frame, int x, int, int c) {
        const int bar = 2 + 2 * (frame - 1);
        return (x >= bar && x < bar + 4 ? 0.1f : 1.0f) * (0.8f + 0.1f * c);
    };
    TempDir dir;
    testkit::write_sequence(
        dir.file("in.%04d.exr"), all_frames(), layout(),
        [&](int frame, int x, int y, int c) { return truth(frame, x, y, c) + noise(frame, x, y, c); });
    const std::string input = "denoise " + dir.file("in.####.exr") + " -q ";
    auto plain = run_modestack(input + "--estimators rebuild -o " + dir.file("plain/d.####.exr"));
    REQUIRE_MESSAGE(plain.exit_code == 0, plain.err);
    auto chosen = run_modestack(input + "--json " + dir.file("s.json") + // the default: every estimator
                                " -o " + dir.file("chosen/d.####.exr"));
    REQUIRE_MESSAGE(chosen.exit_code == 0, chosen.err);
    auto error = [&](const std::string& pattern) { return shot_mse(pattern, truth); };
    const double plain_error = error(dir.file("plain/d.%04d.exr")),
                 chosen_error = error(dir.file("chosen/d.%04d.exr"));
    MESSAGE("MSE: rebuild alone " << plain_error << ", with the choice " << chosen_error << " (noise 0.01)");
    CHECK(chosen_error < 0.7 * plain_error);
    CHECK(chosen_error < 0.01);
    auto estimators = load_json(dir.file("s.json"))["method"]["estimators"];
    CHECK(estimators["set"] == nlohmann::json::array({"rebuild", "input", "spatial", "nlmeans"}));
    REQUIRE(estimators["frames"].size() == kFrames);
    for (const auto& frame : estimators["frames"]) {
        double total = 0;
        for (const auto& [name, value] : frame["share"].items())
            total += value.get<double>();
        CHECK(total == doctest::Approx(1.0));
        CHECK(frame["estimated_rms_error"]["rebuild"].get<double>() >= 0.0);
    }
    CHECK(estimators["frames"][0]["frame"] == 1);
    // Each frame's noise level over the shot's, which the one-sided test uses: positive, mean 1.
    const auto factors = load_json(dir.file("s.json"))["layers"][0]["frame_noise_factors"];
    REQUIRE(factors.size() == kFrames);
    double sum = 0;
    for (const auto& factor : factors) {
        CHECK(factor.get<double>() > 0.0);
        sum += factor.get<double>();
    }
    CHECK(sum / kFrames == doctest::Approx(1.0));
}

TEST_CASE("denoise method options: bad values and combinations exit 2 with one line, nothing written")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), all_frames(), layout(), noisy_value);
    const std::string out = " -q -o " + dir.file("out/d.####.exr");
    struct Case {
        std::string arguments;
        std::string message;
    };
    std::vector<Case> cases{
        {"--transform exp", "--transform 'exp'"},
        {"--transform pow:0.5", "--transform 'pow:0.5'"},
        {"--transform log:-1", "--transform 'log:-1'"},
        {"--shrink soft", "--shrink 'soft'"},
        {"--shrink optimal", "--shrink optimal needs --no-mode-filter"},
        {"--non-negative-mode clamp", "--non-negative-mode needs --non-negative"},
        {"--non-negative --non-negative-mode zero", "--non-negative-mode 'zero'"},
        {"--non-negative --non-negative-mode keep-sum --transform log", "--non-negative-mode keep-sum"},
        {"--segments 1-5,7-12", "--segments '1-5,7-12'"},
        {"--segments 1-2,3-12", "--segments '1-2,3-12'"},
        {"--segments auto --save-modes " + dir.file("modes"),
         "--segments cannot be combined with --save-modes"},
        {"--no-mode-filter --segments auto --train-frames 1-12x3",
         "--segments cannot be combined with --train-frames"},
        {"--train-frames 1-12x3", "--train-frames needs --no-mode-filter"},
        {"--no-mode-filter --train-frames 10-20", "--train-frames '10-20': frame 13 is not in the shot"},
        {"--no-mode-filter --train-frames 1,2", "--train-frames gives 2 frames"},
        {"--no-mode-filter --train-frames 1-12x4 --rank 3", "--rank 3 needs more than 3 training frames"},
        {"--whiten maybe", "--whiten 'maybe'"},
        {"--frame-noise uneven", "--frame-noise 'uneven' is not one of measured, even"},
        {"--weight-smoothing --no-weight-smoothing",
         "--weight-smoothing and --no-weight-smoothing contradict"},
        {"--whiten on --transform log", "--whiten on cannot be combined with --transform log"},
        {"--mode-filter-guides albedo,shadows", "--mode-filter-guides 'shadows'"},
        {"--mode-filter-guides depth,depth", "--mode-filter-guides names 'depth' twice"},
        {"--no-mode-filter --rank-map " + dir.file("r.exr"), "--rank-map needs the mode filter"},
        {"--segments auto --rank-map " + dir.file("r.exr"), "--rank-map cannot be combined with --segments"},
        {"--estimators rebuild,median", "--estimators: unknown estimator 'median'"},
        {"--estimators input --rank-map " + dir.file("r.exr"),
         "--estimators cannot be combined with --rank-map"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack("denoise " + dir.file("in.####.exr") + " " + c.arguments + out);
        CHECK(result.exit_code == 2);
        CHECK(result.err.find('\n') == result.err.size() - 1);
        CHECK_MESSAGE(result.err.find(c.message) != std::string::npos, result.err);
        CHECK_FALSE(std::ifstream(dir.file("out/d.0001.exr")).good());
        if (std::ifstream(dir.file("out")).good())
            CHECK(testkit::list_directory(dir.file("out")).empty());
        CHECK_FALSE(std::ifstream(dir.file("modes")).good());
    }
}
