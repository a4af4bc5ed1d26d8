// End-to-end: refine for any renderer, with `modestack render` playing the
// other renderer. `refine --masks-only` chooses the same pixels as the
// in-process refine; `render --mask` re-renders them at the refine's spp and
// seed; `refine --blend` then gives the in-process refine's frames: every
// channel bit for bit except the re-rendered layer's values, which differ only
// by the re-render's storage in half (as renderers write colour AOVs). Crop
// windows placed by their EXR data window, one file per window, blend like
// full frames. Bad
// re-renders (wrong size, a crop that misses a weighted pixel, no variance)
// fail with one line naming the file and write nothing.
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kWidth = 64, kHeight = 48;
const std::vector<std::string> kIndirect{"DiffInd.R", "DiffInd.G", "DiffInd.B"};
const std::vector<std::string> kVariance{"DiffIndVar.R", "DiffIndVar.G", "DiffIndVar.B"};
const std::vector<int> kFrames{30, 31, 32, 33, 34};

std::string frame_file(const TempDir& dir, const std::string& name, int frame)
{
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%s.%04d.exr", name.c_str(), frame);
    return dir.file(buffer);
}

// `switch` at 64x48 around the crossing, 4 spp, denoised; refined in process
// (64 spp, seed 2: refine's defaults but the spp) and by masks-only + render + blend.
struct ExternalShot {
    TempDir dir;
    std::string selection = " --frames 30-34 --budget 4 --dilate 1 --feather 3 -q ";
    ExternalShot()
    {
        auto render = run_modestack("render --scene switch --frames 26-37 --spp 4 --size 64x48 -q -o " +
                                    dir.file("noisy.####.exr"));
        REQUIRE_MESSAGE(render.exit_code == 0, render.err);
        auto denoise = run_modestack("denoise " + dir.file("noisy.####.exr") + " --layer DiffInd -q -o " +
                                     dir.file("denoised.####.exr"));
        REQUIRE_MESSAGE(denoise.exit_code == 0, denoise.err);
        auto in_process =
            run_modestack("refine --scene switch --size 64x48 --spp 64" + selection + "--denoised " +
                          dir.file("denoised.####.exr") + " -o " + dir.file("in_process.####.exr") +
                          " --masks " + dir.file("in_process_mask.####.exr"));
        REQUIRE_MESSAGE(in_process.exit_code == 0, in_process.err);
        auto masks =
            run_modestack("refine --masks-only" + selection + "--denoised " + dir.file("denoised.####.exr") +
                          " --masks " + dir.file("mask.####.exr") + " --windows " + dir.file("windows.json"));
        REQUIRE_MESSAGE(masks.exit_code == 0, masks.err);
        auto high =
            run_modestack("render --scene switch --frames 30-34 --spp 64 --seed 2 --size 64x48 -q --mask " +
                          dir.file("mask.####.exr") + " -o " + dir.file("high.####.exr"));
        REQUIRE_MESSAGE(high.exit_code == 0, high.err);
    }
    testkit::CliResult blend(const std::string& high, const std::string& output,
                             const std::string& extra = "")
    {
        return run_modestack("refine -q --frames 30-34 --blend " + dir.file(high + ".####.exr") +
                             " --denoised " + dir.file("denoised.####.exr") + " --masks " +
                             dir.file("mask.####.exr") + " -o " + dir.file(output + ".####.exr") + " " +
                             extra);
    }
};

ExternalShot& shared_shot()
{
    static ExternalShot shot;
    return shot;
}

// Writes a crop of a full-frame re-render: only `window`'s pixels, placed by the data window.
void write_crop(const std::string& full_frame, const std::string& path, int x0, int y0, int x1, int y1)
{
    std::vector<std::string> names = kIndirect;
    names.insert(names.end(), kVariance.begin(), kVariance.end());
    std::vector<float> full = testkit::read_channels(full_frame, names), crop;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 6; ++c)
                crop.push_back(full[(static_cast<size_t>(y) * kWidth + x) * 6 + c]);
    OIIO::ImageSpec spec(x1 - x0, y1 - y0, 6, OIIO::TypeFloat);
    spec.x = x0;
    spec.y = y0;
    spec.full_x = 0;
    spec.full_y = 0;
    spec.full_width = kWidth;
    spec.full_height = kHeight;
    spec.channelnames = names;
    spec.channelformats = {OIIO::TypeHalf,  OIIO::TypeHalf,  OIIO::TypeHalf,
                           OIIO::TypeFloat, OIIO::TypeFloat, OIIO::TypeFloat};
    auto output = OIIO::ImageOutput::create(path);
    REQUIRE(output);
    REQUIRE(output->open(path, spec));
    REQUIRE(output->write_image(OIIO::TypeFloat, crop.data()));
    REQUIRE(output->close());
}

nlohmann::json read_json(const std::string& path)
{
    std::ifstream file(path);
    return nlohmann::json::parse(file);
}

} // namespace

TEST_CASE("refine --masks-only chooses the in-process refine's pixels and windows that cover them")
{
    ExternalShot& shot = shared_shot();
    auto json = read_json(shot.dir.file("windows.json"));
    REQUIRE(json["per_frame"].size() == kFrames.size());
    std::int64_t to_render = 0;
    for (size_t i = 0; i < kFrames.size(); ++i) {
        const int frame = kFrames[i];
        auto mask = testkit::read_channels(frame_file(shot.dir, "mask", frame), {"mask", "weight"});
        auto in_process =
            testkit::read_channels(frame_file(shot.dir, "in_process_mask", frame), {"mask", "weight"});
        CHECK(mask == in_process); // the same rule, the same weights (stored in float)
        const auto& entry = json["per_frame"][i];
        CHECK(entry["frame"].get<int>() == frame);
        int pixels = 0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                const size_t p = static_cast<size_t>(y) * kWidth + x;
                CHECK(mask[p * 2] == (mask[p * 2 + 1] > 0 ? 1.0f : 0.0f));
                if (mask[p * 2] == 0.0f)
                    continue;
                ++pixels;
                bool covered = false;
                for (const auto& window : entry["windows"])
                    covered = covered || (x >= window["x0"].get<int>() && x < window["x1"].get<int>() &&
                                          y >= window["y0"].get<int>() && y < window["y1"].get<int>());
                CHECK(covered);
            }
        CHECK(entry["pixels_to_render"].get<int>() == pixels);
        to_render += pixels;
        for (const auto& window : entry["windows"]) {
            CHECK(window["arnold"]["region_max_x"].get<int>() == window["x1"].get<int>() - 1);
            CHECK(window["arnold"]["region_min_y"].get<int>() == window["y0"].get<int>());
        }
    }
    CHECK(to_render > 0);
    CHECK(json["pixels_to_render"].get<std::int64_t>() == to_render);
    CHECK(json["window_overhead_pixels"].get<int>() == 4096);
}

TEST_CASE("refine --blend of another renderer's re-render equals the in-process refine")
{
    ExternalShot& shot = shared_shot();
    auto blend = shot.blend("high", "blended", "--json " + shot.dir.file("blend.json"));
    REQUIRE_MESSAGE(blend.exit_code == 0, blend.err);
    int exact = 0, within = 0, blended = 0;
    for (int frame : kFrames) {
        const std::string in_process = frame_file(shot.dir, "in_process", frame),
                          external = frame_file(shot.dir, "blended", frame);
        auto names = testkit::read_channel_names(in_process);
        REQUIRE(names == testkit::read_channel_names(external));
        std::vector<std::string> others;
        for (const auto& name : names)
            if (std::find(kIndirect.begin(), kIndirect.end(), name) == kIndirect.end())
                others.push_back(name);
        // Sigma (from the float variance: the same samples), the weight and every other channel: bit for bit.
        CHECK(testkit::read_channels(external, others) == testkit::read_channels(in_process, others));
        // The values: the in-process blend used the render's float, --blend its half in the file, so
        // |difference| <= w·|r_half|·2^-11 (half rounding) + one ulp of the output's half (2^-10 relative).
        auto a = testkit::read_channels(in_process, kIndirect),
             b = testkit::read_channels(external, kIndirect);
        auto high = testkit::read_channels(frame_file(shot.dir, "high", frame), kIndirect);
        auto weight = testkit::read_channels(external, {"DiffInd.refine_weight"});
        for (size_t p = 0; p < weight.size(); ++p)
            for (int c = 0; c < 3; ++c) {
                const size_t i = p * 3 + c;
                if (weight[p] == 0.0f) {
                    CHECK(a[i] == b[i]);
                    continue;
                }
                ++blended;
                const double bound = weight[p] * std::fabs(high[i]) * std::ldexp(1.0, -11) +
                                     std::fabs(a[i]) * std::ldexp(1.0, -10) + 1e-7;
                exact += a[i] == b[i] ? 1 : 0;
                within += std::fabs(a[i] - b[i]) <= bound ? 1 : 0;
                if (std::fabs(a[i] - b[i]) > bound)
                    CHECK_MESSAGE(false,
                                  "frame " << frame << " pixel " << p << ": " << a[i] << " vs " << b[i]);
            }
    }
    MESSAGE(blended << " blended values: " << exact << " bit-identical, " << within << " within the bound");
    CHECK(blended > 0);
    CHECK(within == blended);
    auto json = read_json(shot.dir.file("blend.json"));
    CHECK(json["estimated_relmse_after"].get<double>() < json["estimated_relmse_before"].get<double>());
}

TEST_CASE("refine --blend places crop windows by their data window: the same frames as full frames")
{
    ExternalShot& shot = shared_shot();
    REQUIRE(shot.blend("high", "from_full").exit_code == 0);
    // Windows without overhead (several a frame), each rendered as its own crop file, as a farm would.
    auto windows =
        run_modestack("refine --masks-only" + shot.selection + "--window-overhead 0 --denoised " +
                      shot.dir.file("denoised.####.exr") + " --masks " + shot.dir.file("mask0.####.exr") +
                      " --windows " + shot.dir.file("windows0.json"));
    REQUIRE_MESSAGE(windows.exit_code == 0, windows.err);
    auto json = read_json(shot.dir.file("windows0.json"));
    int crops = 0;
    for (size_t i = 0; i < kFrames.size(); ++i) {
        CHECK(testkit::read_channels(frame_file(shot.dir, "mask0", kFrames[i]), {"weight"}) ==
              testkit::read_channels(frame_file(shot.dir, "mask", kFrames[i]), {"weight"}));
        for (const auto& window : json["per_frame"][i]["windows"]) {
            char name[64];
            std::snprintf(name, sizeof name, "crop.%04d.w%d.exr", kFrames[i], window["index"].get<int>());
            write_crop(frame_file(shot.dir, "high", kFrames[i]), shot.dir.file(name), window["x0"].get<int>(),
                       window["y0"].get<int>(), window["x1"].get<int>(), window["y1"].get<int>());
            ++crops;
        }
    }
    MESSAGE(crops << " crop windows in " << kFrames.size() << " frames");
    CHECK(crops > static_cast<int>(kFrames.size())); // several windows in some frame
    auto from_crops =
        run_modestack("refine -q --frames 30-34 --blend " + shot.dir.file("crop.####.w{window}.exr") +
                      " --denoised " + shot.dir.file("denoised.####.exr") + " --masks " +
                      shot.dir.file("mask.####.exr") + " -o " + shot.dir.file("from_crops.####.exr"));
    REQUIRE_MESSAGE(from_crops.exit_code == 0, from_crops.err);
    for (int frame : kFrames) {
        auto names = testkit::read_channel_names(frame_file(shot.dir, "from_full", frame));
        CHECK(testkit::read_channels(frame_file(shot.dir, "from_crops", frame), names) ==
              testkit::read_channels(frame_file(shot.dir, "from_full", frame), names));
    }
}

TEST_CASE("refine --blend refuses a wrong-size re-render, a crop that misses pixels and a missing variance")
{
    ExternalShot& shot = shared_shot();
    auto small = run_modestack("render --scene switch --frames 30-34 --spp 1 --size 32x24 -q -o " +
                               shot.dir.file("small.####.exr"));
    REQUIRE(small.exit_code == 0);
    // A crop of frame 32 one pixel short of its weighted pixels; the other frames whole.
    auto json = read_json(shot.dir.file("windows.json"));
    int frame_with_pixels = -1;
    for (size_t i = 0; i < kFrames.size() && frame_with_pixels < 0; ++i)
        if (json["per_frame"][i]["pixels_to_render"].get<int>() > 0)
            frame_with_pixels = static_cast<int>(i);
    REQUIRE(frame_with_pixels >= 0);
    for (size_t i = 0; i < kFrames.size(); ++i) {
        const auto& window = json["per_frame"][i]["windows"];
        const bool short_one = static_cast<int>(i) == frame_with_pixels;
        const int x1 = short_one ? window[0]["x1"].get<int>() - 1 : kWidth;
        write_crop(frame_file(shot.dir, "high", kFrames[i]), frame_file(shot.dir, "short", kFrames[i]),
                   short_one ? window[0]["x0"].get<int>() : 0, short_one ? window[0]["y0"].get<int>() : 0, x1,
                   short_one ? window[0]["y1"].get<int>() : kHeight);
    }
    const std::string short_file = frame_file(shot.dir, "short", kFrames[frame_with_pixels]);
    struct Case {
        std::string high, extra, says;
    };
    for (const Case& bad :
         {Case{"small", "",
               frame_file(shot.dir, "small", 30) +
                   ": the re-render is 32x24 but the denoised frames are 64x48"},
          Case{"short", "", short_file + ": the re-render of frame"},
          Case{"high", "--blend-variance DiffIndVariance", "layer 'DiffIndVariance' not found"}}) {
        CAPTURE(bad.high);
        auto result = shot.blend(bad.high, "out/blended", bad.extra);
        CHECK(result.exit_code == 1);
        CHECK_MESSAGE(result.err.find(bad.says) != std::string::npos, result.err);
        CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);
        CHECK(!std::filesystem::exists(shot.dir.file("out"))); // every input is checked before any output
    }
}

TEST_CASE("refine --masks-only and --blend refuse options that belong to the other half")
{
    TempDir dir;
    struct Case {
        std::string arguments, says;
    };
    for (const Case& bad :
         {Case{"--masks-only --denoised d.####.exr --masks m.####.exr -o o.####.exr", "drop -o"},
          Case{"--masks-only --denoised d.####.exr", "--masks-only needs --masks"},
          Case{"--blend h.####.exr --denoised d.####.exr -o o.####.exr", "--blend needs --masks"},
          Case{"--masks-only --blend h.####.exr --denoised d.####.exr --masks m.####.exr", "give one"},
          Case{"--masks-only --scene switch --denoised d.####.exr --masks m.####.exr",
               "--scene is for the built-in re-render"}}) {
        CAPTURE(bad.arguments);
        auto result = run_modestack("refine -q " + bad.arguments);
        CHECK(result.exit_code == 2);
        CHECK(result.err.find(bad.says) != std::string::npos);
    }
}
