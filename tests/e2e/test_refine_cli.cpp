// End-to-end: `modestack refine` on a small render of `switch` fixes the frames
// where the crossing box is erased by the denoiser (lower error than before
// refine, no higher than the noisy input), blends without a seam, leaves every
// other pixel and channel alone, does nothing with --budget 0, gives the same
// pixels for any --threads, and refuses bad inputs with one line and no output.
// `modestack run` writes every promised output, the same pixels for any --threads,
// and denoised frames with the bits of the denoise stages run by hand one after
// another (DiffDir, then DiffInd on its output), which run does in one pass.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kWidth = 64, kHeight = 48;
const std::vector<std::string> kIndirect{"DiffInd.R", "DiffInd.G", "DiffInd.B"};
const std::vector<std::string> kSigma{"DiffInd.sigma.R", "DiffInd.sigma.G", "DiffInd.sigma.B"};

std::string frame_file(const TempDir& dir, const std::string& name, int frame)
{
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%s.%04d.exr", name.c_str(), frame);
    return dir.file(buffer);
}

double relative_mse(const std::vector<float>& x, const std::vector<float>& r)
{
    double sum = 0;
    for (size_t i = 0; i < x.size(); ++i)
        sum += (x[i] - r[i]) * (x[i] - r[i]) / (r[i] * r[i] + 0.01);
    return sum / x.size();
}

// A 64x48 shot of `switch` around the crossing (frames 26-41, the light is still),
// rendered at 4 spp and denoised; refined in frames 29-37 only (the test's time).
struct SwitchShot {
    TempDir dir;
    std::string size = " --size 64x48 ";
    SwitchShot()
    {
        auto render = run_modestack("render --scene switch --frames 26-41 --spp 4 -q" + size + "-o " +
                                    dir.file("noisy.####.exr"));
        REQUIRE_MESSAGE(render.exit_code == 0, render.err);
        auto denoise = run_modestack("denoise " + dir.file("noisy.####.exr") + " --layer DiffInd -q -o " +
                                     dir.file("denoised.####.exr"));
        REQUIRE_MESSAGE(denoise.exit_code == 0, denoise.err);
    }
    testkit::CliResult refine(const std::string& output, const std::string& extra,
                              const std::string& frames = "29-37")
    {
        return run_modestack("refine --scene switch --frames " + frames +
                             " --spp 64 --dilate 1 --feather 3 -q" + size + "--denoised " +
                             dir.file("denoised.####.exr") + " -o " + dir.file(output + ".####.exr") + " " +
                             extra);
    }
};

SwitchShot& shared_shot()
{
    static SwitchShot shot;
    return shot;
}

} // namespace

TEST_CASE(
    "refine lowers the error where the crossing box is, stays within the noisy error, and shows no seam")
{
    SwitchShot& shot = shared_shot();
    auto refine = shot.refine("refined", "--budget 4 --json " + shot.dir.file("refine.json"));
    REQUIRE_MESSAGE(refine.exit_code == 0, refine.err);
    auto reference = run_modestack("render --scene switch --frames 30-36 --spp 128 --seed 3 -q" + shot.size +
                                   "-o " + shot.dir.file("reference.####.exr"));
    REQUIRE_MESSAGE(reference.exit_code == 0, reference.err);

    double border_step = 0, inside_step = 0, whole[3] = {0, 0, 0};
    int border_pairs = 0, inside_pairs = 0;
    for (int frame = 30; frame <= 36; ++frame) {
        auto truth = testkit::read_channels(frame_file(shot.dir, "reference", frame), kIndirect);
        auto noisy = testkit::read_channels(frame_file(shot.dir, "noisy", frame), kIndirect);
        auto denoised = testkit::read_channels(frame_file(shot.dir, "denoised", frame), kIndirect);
        auto refined = testkit::read_channels(frame_file(shot.dir, "refined", frame), kIndirect);
        auto weight =
            testkit::read_channels(frame_file(shot.dir, "refined", frame), {"DiffInd.refine_weight"});
        double e_noisy = relative_mse(noisy, truth), e_denoised = relative_mse(denoised, truth),
               e_refined = relative_mse(refined, truth);
        MESSAGE("frame " << frame << " relMSE noisy " << e_noisy << " denoised " << e_denoised << " refined "
                         << e_refined);
        whole[0] += e_noisy;
        whole[1] += e_denoised;
        whole[2] += e_refined;
        // Where refine acted, per frame: the same comparison on those pixels only.
        std::vector<float> region[4];
        for (size_t p = 0; p < weight.size(); ++p)
            if (weight[p] > 0)
                for (int c = 0; c < 3; ++c)
                    for (int k = 0; k < 4; ++k)
                        region[k].push_back((k == 0   ? truth
                                             : k == 1 ? noisy
                                             : k == 2 ? denoised
                                                      : refined)[p * 3 + c]);
        if (!region[0].empty()) {
            double r_noisy = relative_mse(region[1], region[0]),
                   r_denoised = relative_mse(region[2], region[0]),
                   r_refined = relative_mse(region[3], region[0]);
            MESSAGE("  refined pixels: " << weight.size() - std::count(weight.begin(), weight.end(), 0.0f)
                                         << ", relMSE there: noisy " << r_noisy << " denoised " << r_denoised
                                         << " refined " << r_refined);
            CHECK(r_refined < r_denoised);
            CHECK(r_refined <= r_noisy);
        }

        // Seam: the relative error field must not step at the feathered border more
        // than it varies between neighbours inside the re-rendered region (noise).
        auto error_at = [&](int p) {
            double sum = 0;
            for (int c = 0; c < 3; ++c)
                sum += (refined[p * 3 + c] - truth[p * 3 + c]) / (std::fabs(truth[p * 3 + c]) + 0.1);
            return sum / 3;
        };
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x + 1 < kWidth; ++x) {
                int p = y * kWidth + x, q = p + 1;
                double step = std::fabs(error_at(p) - error_at(q));
                if (weight[p] == 1.0f && weight[q] == 1.0f) {
                    inside_step += step;
                    ++inside_pairs;
                } else if (weight[p] != weight[q]) {
                    border_step += step;
                    ++border_pairs;
                }
            }
    }
    // Over the crossing frames, whole frames: lower than before refine, no higher than noisy.
    CHECK(whole[2] < whole[1]);
    CHECK(whole[2] <= whole[0]);
    REQUIRE(inside_pairs > 0);
    REQUIRE(border_pairs > 0);
    MESSAGE("mean error step: border " << border_step / border_pairs << ", inside "
                                       << inside_step / inside_pairs);
    CHECK(border_step / border_pairs <= 1.25 * inside_step / inside_pairs);

    std::ifstream json_file(shot.dir.file("refine.json"));
    auto json = nlohmann::json::parse(json_file);
    CHECK(json["per_frame"].size() == 9);
    CHECK(json["percent_rendered"].get<double>() > 4.0);
    CHECK(json["estimated_relmse_after"].get<double>() < json["estimated_relmse_before"].get<double>());
}

TEST_CASE("refine leaves unweighted pixels and every other channel bit-exact, and --budget 0 changes nothing")
{
    SwitchShot& shot = shared_shot();
    auto refine = shot.refine("partial", "--budget 5 --masks " + shot.dir.file("mask.####.exr"));
    REQUIRE_MESSAGE(refine.exit_code == 0, refine.err);
    auto none = shot.refine("none", "--budget 0");
    REQUIRE_MESSAGE(none.exit_code == 0, none.err);
    int refined_pixels = 0;
    for (int frame : {30, 33, 37}) {
        std::string input = frame_file(shot.dir, "denoised", frame),
                    output = frame_file(shot.dir, "partial", frame);
        std::vector<std::string> names = testkit::read_channel_names(input), others;
        for (const auto& name : names)
            if (name.rfind("DiffInd.", 0) != 0)
                others.push_back(name);
        CHECK(testkit::read_channels(output, others) == testkit::read_channels(input, others));
        auto weight = testkit::read_channels(output, {"DiffInd.refine_weight"});
        auto mask = testkit::read_channels(frame_file(shot.dir, "mask", frame), {"mask", "weight"});
        auto before =
            testkit::read_channels(input, {"DiffInd.R", "DiffInd.G", "DiffInd.B", "DiffInd.sigma.R"});
        auto after =
            testkit::read_channels(output, {"DiffInd.R", "DiffInd.G", "DiffInd.B", "DiffInd.sigma.R"});
        int untouched = 0;
        for (size_t p = 0; p < weight.size(); ++p) {
            CHECK(mask[p * 2] == (weight[p] > 0 ? 1.0f : 0.0f));
            // The mask keeps the weight in float; the output stores it in DiffInd's half.
            CHECK(mask[p * 2 + 1] == doctest::Approx(weight[p]).epsilon(1e-3));
            if (weight[p] == 0.0f) {
                ++untouched;
                for (int c = 0; c < 4; ++c)
                    CHECK(after[p * 4 + c] == before[p * 4 + c]);
            }
        }
        CHECK(untouched > 0);
        refined_pixels += static_cast<int>(weight.size()) - untouched;

        // --budget 0: the same channels as the input plus a zero weight, every value equal.
        std::string untouched_output = frame_file(shot.dir, "none", frame);
        CHECK(testkit::read_channels(untouched_output, names) == testkit::read_channels(input, names));
        auto zero = testkit::read_channels(untouched_output, {"DiffInd.refine_weight"});
        CHECK(std::all_of(zero.begin(), zero.end(), [](float w) { return w == 0.0f; }));
    }
    CHECK(refined_pixels > 0);
}

TEST_CASE("refine --by-gain: the least gain is what the samples would buy spread over the shot, and it rises "
          "with the refine spp")
{
    SwitchShot& shot = shared_shot();
    auto at_64 = shot.refine("gain64", "--by-gain --json " + shot.dir.file("gain64.json"));
    REQUIRE_MESSAGE(at_64.exit_code == 0, at_64.err);
    auto at_256 =
        run_modestack("refine --scene switch --frames 29-37 --spp 256 --by-gain -q" + shot.size +
                      "--denoised " + shot.dir.file("denoised.####.exr") + " -o " +
                      shot.dir.file("gain256.####.exr") + " --json " + shot.dir.file("gain256.json"));
    REQUIRE_MESSAGE(at_256.exit_code == 0, at_256.err);
    const auto low = nlohmann::json::parse(std::ifstream(shot.dir.file("gain64.json")));
    const auto high = nlohmann::json::parse(std::ifstream(shot.dir.file("gain256.json")));
    CHECK(low["selection"] == "gain");
    CHECK(low["input_spp"] == 4); // from the frames' modestack:spp
    // 64 spp where the input has 4: a re-rendered pixel costs what 16 more spp on one pixel
    // of the shot would, which lower its predicted relMSE by 16 / 4 of its own.
    const double predicted = low["estimated_relmse_before"].get<double>();
    CHECK(low["threshold"].get<double>() == doctest::Approx(64.0 / 4 * predicted).epsilon(1e-5));
    CHECK(high["threshold"].get<double>() == doctest::Approx(256.0 / 4 * predicted).epsilon(1e-5));
    // Samples cost more at 256 spp than the lower noise gains: no more pixels than at 64.
    CHECK(low["pixels_selected"].get<int>() > 0);
    CHECK(high["pixels_selected"].get<int>() <= low["pixels_selected"].get<int>());
    CHECK(low["estimated_relmse_after"].get<double>() < predicted);
    for (int frame : {30, 33}) {
        auto weight =
            testkit::read_channels(frame_file(shot.dir, "gain64", frame), {"DiffInd.refine_weight"});
        CHECK(std::all_of(weight.begin(), weight.end(), [](float w) { return w >= 0.0f && w <= 1.0f; }));
    }
}

TEST_CASE("refine gives the same pixels for --threads 1 and 2")
{
    SwitchShot& shot = shared_shot();
    REQUIRE(shot.refine("one", "--budget 3 --threads 1", "33-34").exit_code == 0);
    REQUIRE(shot.refine("two", "--budget 3 --threads 2", "33-34").exit_code == 0);
    for (int frame : {33, 34}) {
        auto names = testkit::read_channel_names(frame_file(shot.dir, "one", frame));
        CHECK(testkit::read_channels(frame_file(shot.dir, "one", frame), names) ==
              testkit::read_channels(frame_file(shot.dir, "two", frame), names));
    }
}

TEST_CASE(
    "refine refuses a sequence without sigma, frames outside the scene and a size mismatch, writing nothing")
{
    TempDir dir;
    testkit::ExrLayout plain;
    plain.width = 16;
    plain.height = 12;
    plain.channel_names = {"DiffInd.R", "DiffInd.G", "DiffInd.B"};
    testkit::write_sequence(dir.file("plain.%04d.exr"), {1, 2, 3}, plain,
                            [](int, int, int, int) { return 0.5f; });
    testkit::ExrLayout with_sigma = plain;
    with_sigma.channel_names.insert(with_sigma.channel_names.end(), kSigma.begin(), kSigma.end());
    testkit::write_sequence(dir.file("late.%04d.exr"), {47, 48, 49}, with_sigma,
                            [](int, int, int, int) { return 0.5f; });
    testkit::write_sequence(dir.file("small.%04d.exr"), {1, 2, 3}, with_sigma,
                            [](int, int, int, int) { return 0.5f; });

    struct Case {
        std::string input, extra, says;
    };
    for (const Case& bad : {Case{"plain", "--size 16x12", "no DiffInd.sigma channels"},
                            Case{"late", "--size 16x12", "frame 49 is outside scene 'switch' (frames 1-48)"},
                            Case{"small", "", "the frames are 16x12 but --size is 320x240"}}) {
        auto result =
            run_modestack("refine --scene switch -q --denoised " + dir.file(bad.input + ".####.exr") +
                          " -o " + dir.file("out/refined.####.exr") + " " + bad.extra);
        CAPTURE(bad.input);
        CHECK(result.exit_code == 1);
        CHECK(result.err.find(bad.says) != std::string::npos);
        CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);
        CHECK(!std::filesystem::exists(dir.file("out")));
    }
}

TEST_CASE("run writes every output and the same pixels for --threads 1 and 2, refining by gain by default")
{
    TempDir dir;
    std::string common = "run --scene switch --size 32x24 --frames 30-37 --refine-spp 16 -q ";
    auto one = run_modestack(common + "--threads 1 -o " + dir.file("one"));
    REQUIRE_MESSAGE(one.exit_code == 0, one.err);
    auto two = run_modestack(common + "--threads 2 --reference-spp 32 -o " + dir.file("two"));
    REQUIRE_MESSAGE(two.exit_code == 0, two.err);
    for (const char* folder : {"noisy", "denoised", "refined", "final", "masks"})
        CHECK(testkit::list_directory(dir.file(std::string("one/") + folder)).size() == 8);
    CHECK_FALSE(std::filesystem::exists(dir.file("one/direct"))); // both layers in one denoise pass
    // By hand, as run did before: DiffDir, then DiffInd (whitened by DiffIndVar) on its output. The same
    // bits, though run renders in its own process first (whose threads must not change the decode).
    const std::string by_hand = "denoise --no-update-beauty -q ";
    auto direct = run_modestack(by_hand + dir.file("one/noisy/switch.####.exr") + " --layer DiffDir -o " +
                                dir.file("hand_direct/d.####.exr"));
    REQUIRE_MESSAGE(direct.exit_code == 0, direct.err);
    auto indirect = run_modestack(by_hand + dir.file("hand_direct/d.####.exr") + " --layer DiffInd -o " +
                                  dir.file("hand/d.####.exr"));
    REQUIRE_MESSAGE(indirect.exit_code == 0, indirect.err);
    for (int frame = 30; frame <= 37; ++frame) {
        CAPTURE(frame);
        char run_name[64], hand_name[64];
        std::snprintf(run_name, sizeof run_name, "one/denoised/switch.%04d.exr", frame);
        std::snprintf(hand_name, sizeof hand_name, "hand/d.%04d.exr", frame);
        for (const char* layer : {"DiffDir", "DiffInd"}) {
            std::vector<std::string> channels;
            for (const char* suffix : {".R", ".G", ".B", ".sigma.R", ".sigma.G", ".sigma.B"})
                channels.push_back(layer + std::string(suffix));
            CHECK(testkit::read_channels(dir.file(run_name), channels) ==
                  testkit::read_channels(dir.file(hand_name), channels));
        }
    }
    CHECK(std::filesystem::exists(dir.file("two/contact_sheet.png")));
    for (int frame : {30, 33, 37}) {
        char name[64];
        std::snprintf(name, sizeof name, "final/switch.%04d.exr", frame);
        std::string a = dir.file(std::string("one/") + name), b = dir.file(std::string("two/") + name);
        auto names = testkit::read_channel_names(a);
        CHECK(testkit::read_channels(a, names) == testkit::read_channels(b, names));
        // The final beauty is the composite of the refined passes.
        auto passes =
            testkit::read_channels(a, {"Combined.G", "DiffCol.G", "DiffDir.G", "DiffInd.G", "Emit.G"});
        for (size_t p = 0; p < passes.size() / 5; ++p)
            CHECK(passes[p * 5] ==
                  doctest::Approx(passes[p * 5 + 1] * (passes[p * 5 + 2] + passes[p * 5 + 3]) +
                                  passes[p * 5 + 4])
                      .epsilon(2e-3));
    }
    std::ifstream json_file(dir.file("two/summary.json"));
    auto summary = nlohmann::json::parse(json_file);
    CHECK(summary["rank"].get<int>() >= 1);
    // By default the samples go to an 8-spp noisy pass and refine re-renders only where that pays.
    CHECK(summary["spp"].get<int>() == 8);
    CHECK(summary["refine_selection"] == "gain");
    CHECK(summary["refine_budget_percent"].is_null());
    CHECK(summary["percent_pixels_refined"].get<double>() > 0);
    for (const char* stage : {"render", "denoise", "refine", "composite", "reference"})
        CHECK(summary["seconds"][stage].get<double>() > 0);
    auto relmse = summary["quality"]["DiffInd"]["relmse"];
    CHECK(relmse["denoised"].get<double>() < relmse["noisy"].get<double>());
    // The direct light is denoised too (on its own modes), so the beauty gains at least as much.
    CHECK(summary["direct_rank"].get<int>() >= 1);
    auto beauty = summary["quality"]["beauty"]["relmse"];
    CHECK(beauty["denoised"].get<double>() < beauty["noisy"].get<double>());
    // Its DiffDir differs from the noisy pass's: the run wrote a denoised one.
    const std::string noisy_frame = dir.file("two/noisy/switch.0033.exr"),
                      final_frame = dir.file("two/final/switch.0033.exr");
    CHECK(testkit::read_channels(noisy_frame, {"DiffDir.R", "DiffDir.G", "DiffDir.B"}) !=
          testkit::read_channels(final_frame, {"DiffDir.R", "DiffDir.G", "DiffDir.B"}));
    CHECK(summary["quality"]["DiffInd"]["relmse_crossing_frames"]["refined"].get<double>() > 0);
    // Each beauty of the summary is that stage's own passes: the denoised one from the denoised
    // DiffDir and DiffInd (not the noisy DiffDir), so that it differs from the final by refine alone.
    for (const auto& row : summary["quality"]["per_frame"]) {
        const int frame = row["frame"].get<int>();
        CAPTURE(frame);
        char name[64];
        std::snprintf(name, sizeof name, "switch.%04d.exr", frame);
        const std::vector<std::string> passes{"DiffCol.R", "DiffCol.G", "DiffCol.B", "DiffDir.R",
                                              "DiffDir.G", "DiffDir.B", "DiffInd.R", "DiffInd.G",
                                              "DiffInd.B", "Emit.R",    "Emit.G",    "Emit.B"};
        const auto denoised = testkit::read_channels(dir.file(std::string("two/denoised/") + name), passes);
        std::vector<float> beauty(denoised.size() / 4);
        for (size_t p = 0; p < beauty.size() / 3; ++p)
            for (int c = 0; c < 3; ++c) {
                const float* pass = denoised.data() + p * 12;
                beauty[p * 3 + c] = pass[c] * (pass[3 + c] + pass[6 + c]) + pass[9 + c];
            }
        const auto reference = testkit::read_channels(dir.file(std::string("two/reference/") + name),
                                                      {"Combined.R", "Combined.G", "Combined.B"});
        CHECK(row["beauty"][1].get<double>() ==
              doctest::Approx(relative_mse(beauty, reference)).epsilon(1e-5));
    }
}
