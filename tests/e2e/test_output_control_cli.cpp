// End-to-end: output control of `modestack denoise` (issue 30, item 5) through
// the real binary on small EXR shots written here with OIIO: the compression
// rule (a lossy DWAA or B44 input is written ZIP and its untouched channels
// keep their decoded values; a lossless PIZ input stays PIZ), --compression
// honoured (a lossy one too), per part for a multi-part input; --data-type
// float gives float denoised and sigma channels and leaves the rest half;
// --only-denoised writes just the denoised layer and its sigma (and the beauty
// --update-beauty rewrites), a multi-part input only the denoised layer's part
// under its name; a farm's write task takes these options alone; a bad
// --compression is a usage error of one line.
#include "tests/tools/testkit.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kWidth = 40, kHeight = 36, kFrames = 6;

// A smooth picture that changes slowly over the shot, with noise.
float pixel_value(int frame, int x, int y, int c)
{
    std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.08f);
    const float signal = 0.4f + 0.25f * std::sin(0.21f * x + 0.6f * c) * std::cos(0.17f * y) + 0.02f * frame;
    return std::max(0.0f, signal + normal(generator));
}

// The denoised layer "diffuse" and two layers that pass through: "specular" and an alpha.
testkit::ExrLayout shot_layout(const std::string& compression)
{
    testkit::ExrLayout layout;
    layout.width = kWidth;
    layout.height = kHeight;
    layout.channel_names = {"A",          "diffuse.R",  "diffuse.G", "diffuse.B",
                            "specular.R", "specular.G", "specular.B"};
    layout.compression = compression;
    return layout;
}

std::string write_shot(const TempDir& dir, const std::string& name, const std::string& compression)
{
    std::vector<int> frames;
    for (int frame = 1; frame <= kFrames; ++frame)
        frames.push_back(frame);
    testkit::write_sequence(dir.file(name + ".%04d.exr"), frames, shot_layout(compression), pixel_value);
    return dir.file(name + ".####.exr");
}

std::string frame_file(const std::string& hashes, int frame)
{
    std::string path = hashes;
    char digits[16];
    std::snprintf(digits, sizeof digits, "%04d", frame);
    path.replace(path.find("####"), 4, digits);
    return path;
}

// Every part of a file as OIIO reads it: name, compression, channel names and types.
struct PartInfo {
    std::string name, compression;
    std::vector<std::string> channels;
    std::vector<std::string> types;
};

std::vector<PartInfo> read_parts(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    REQUIRE_MESSAGE(input, OIIO::geterror());
    std::vector<PartInfo> parts;
    for (int subimage = 0; input->seek_subimage(subimage, 0); ++subimage) {
        const OIIO::ImageSpec& spec = input->spec();
        PartInfo part{spec.get_string_attribute("oiio:subimagename"),
                      spec.get_string_attribute("compression"),
                      spec.channelnames,
                      {}};
        for (int c = 0; c < spec.nchannels; ++c)
            part.types.push_back(spec.channelformat(c).c_str());
        parts.push_back(part);
    }
    return parts;
}

std::string type_of(const PartInfo& part, const std::string& channel)
{
    const auto found = std::find(part.channels.begin(), part.channels.end(), channel);
    REQUIRE_MESSAGE(found != part.channels.end(), channel);
    return part.types[static_cast<std::size_t>(found - part.channels.begin())];
}

const std::vector<std::string> kUntouched{"A", "specular.R", "specular.G", "specular.B"};
const std::vector<std::string> kDenoised{"diffuse.R", "diffuse.G", "diffuse.B"};
const std::vector<std::string> kSigma{"diffuse.sigma.R", "diffuse.sigma.G", "diffuse.sigma.B"};

testkit::CliResult denoise(const std::string& input, const std::string& output, const std::string& options)
{
    return run_modestack("denoise " + input + " --layer diffuse -q " + options + " -o " + output);
}

} // namespace

TEST_CASE(
    "denoise output compression: lossy inputs are written ZIP with untouched values unchanged, lossless "
    "ones keep theirs, --compression is honoured")
{
    TempDir dir;
    struct Case {
        std::string input_compression, options, expected;
    };
    for (const Case& run :
         {Case{"dwaa", "", "zip"}, Case{"b44", "", "zip"}, Case{"piz", "", "piz"}, Case{"zip", "", "zip"},
          Case{"zip", "--compression piz", "piz"}, Case{"zips", "--compression dwab:60", "dwab"},
          Case{"dwaa", "--compression none", "none"}}) {
        CAPTURE(run.input_compression);
        CAPTURE(run.options);
        const std::string input = write_shot(dir, "in_" + run.input_compression, run.input_compression);
        REQUIRE(read_parts(frame_file(input, 1))[0].compression.rfind(run.input_compression, 0) == 0);
        const std::string output =
            dir.file("out/" + run.input_compression + "_" + std::to_string(run.options.size()) + ".####.exr");
        const testkit::CliResult result = denoise(input, output, run.options);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
        for (int frame = 1; frame <= kFrames; ++frame) {
            const std::string in_file = frame_file(input, frame), out_file = frame_file(output, frame);
            CHECK(read_parts(out_file)[0].compression.rfind(run.expected, 0) == 0);
            if (run.expected == "dwab")
                continue; // asked for: the untouched channels are re-encoded lossy
            // Decoded values, not bytes: the input decoded once, the output's lossless copy of that.
            CHECK(testkit::read_channels(out_file, kUntouched) ==
                  testkit::read_channels(in_file, kUntouched));
            CHECK(testkit::read_channels(out_file, kDenoised) != testkit::read_channels(in_file, kDenoised));
        }
    }
    // What the default saves: the same DWAA input written DWAA again changes untouched values.
    const std::string again = dir.file("out/again.####.exr");
    const testkit::CliResult lossy = denoise(dir.file("in_dwaa.####.exr"), again, "--compression dwaa");
    REQUIRE_MESSAGE(lossy.exit_code == 0, lossy.err);
    CHECK(read_parts(frame_file(again, 1))[0].compression.rfind("dwaa", 0) == 0);
    bool changed = false;
    for (int frame = 1; frame <= kFrames; ++frame)
        changed = changed ||
                  testkit::read_channels(frame_file(again, frame), kUntouched) !=
                      testkit::read_channels(frame_file(dir.file("in_dwaa.####.exr"), frame), kUntouched);
    CHECK(changed);
}

TEST_CASE("denoise --data-type float: float denoised and sigma channels, untouched channels half")
{
    TempDir dir;
    const std::string input = write_shot(dir, "in", "zip");
    const std::string as_input = dir.file("out/half.####.exr"), as_float = dir.file("out/float.####.exr");
    for (const auto& [output, options] : {std::pair{as_input, ""}, {as_float, "--data-type float"}}) {
        const testkit::CliResult result = denoise(input, output, options);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::string half_file = frame_file(as_input, frame), float_file = frame_file(as_float, frame);
        const PartInfo half_part = read_parts(half_file)[0], float_part = read_parts(float_file)[0];
        for (const std::vector<std::string>* channels : {&kDenoised, &kSigma})
            for (const std::string& channel : *channels) {
                CHECK(type_of(half_part, channel) == "half");
                CHECK(type_of(float_part, channel) == "float");
            }
        for (const std::string& channel : kUntouched)
            CHECK(type_of(float_part, channel) == "half");
        CHECK(testkit::read_native(float_file) != testkit::read_native(half_file));
        CHECK(testkit::read_channels(float_file, kUntouched) ==
              testkit::read_channels(frame_file(input, frame), kUntouched));
        // The same denoised values: the half output holds them rounded.
        for (const std::vector<std::string>* channels : {&kDenoised, &kSigma}) {
            const std::vector<float> floats = testkit::read_channels(float_file, *channels);
            const std::vector<float> halves = testkit::read_channels(half_file, *channels);
            REQUIRE(floats.size() == halves.size());
            std::size_t rounded_equal = 0, not_half = 0;
            for (std::size_t k = 0; k < floats.size(); ++k) {
                rounded_equal += static_cast<float>(Imath::half(floats[k])) == halves[k];
                not_half += static_cast<float>(Imath::half(floats[k])) != floats[k];
            }
            CHECK(rounded_equal == floats.size());
            CHECK(not_half > 0); // float precision kept, not half values widened
        }
    }
}

TEST_CASE(
    "denoise --only-denoised: just the denoised layer and its sigma, and the beauty --update-beauty rewrites")
{
    TempDir dir;
    const std::string input = write_shot(dir, "in", "zip");
    const std::string full = dir.file("out/full.####.exr"), only = dir.file("out/only.####.exr");
    for (const auto& [output, options] : {std::pair{full, "--no-update-beauty"},
                                          {only, "--no-update-beauty --only-denoised --compression piz"}}) {
        const testkit::CliResult result = denoise(input, output, options);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    std::vector<std::string> written = kDenoised;
    written.insert(written.end(), kSigma.begin(), kSigma.end());
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::vector<PartInfo> parts = read_parts(frame_file(only, frame));
        REQUIRE(parts.size() == 1);
        CHECK(std::set<std::string>(parts[0].channels.begin(), parts[0].channels.end()) ==
              std::set<std::string>(written.begin(), written.end()));
        CHECK(parts[0].compression == "piz");
        CHECK(testkit::read_channels(frame_file(only, frame), written) ==
              testkit::read_channels(frame_file(full, frame), written));
    }

    // Our renderer's shot: --update-beauty (on by default there) rewrites Combined, which is kept whole.
    const std::string rendered = dir.file("render.####.exr"), beauty = dir.file("out/beauty.####.exr");
    const testkit::CliResult render =
        run_modestack("render --scene orbit --frames 1-" + std::to_string(kFrames) +
                      " --spp 2 --size 32x24 -q -o " + rendered);
    REQUIRE_MESSAGE(render.exit_code == 0, render.err);
    const testkit::CliResult result =
        run_modestack("denoise " + rendered + " --layer DiffInd --only-denoised -q -o " + beauty);
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    const std::vector<std::string> names = testkit::read_channel_names(frame_file(beauty, 1));
    CHECK(std::set<std::string>(names.begin(), names.end()) ==
          std::set<std::string>{"Combined.R", "Combined.G", "Combined.B", "Combined.A", "Combined.sigma.R",
                                "Combined.sigma.G", "Combined.sigma.B", "DiffInd.R", "DiffInd.G", "DiffInd.B",
                                "DiffInd.sigma.R", "DiffInd.sigma.G", "DiffInd.sigma.B"});
}

TEST_CASE(
    "denoise output control of a multi-part input: the rule per part, --only-denoised keeps the layer's part")
{
    TempDir dir;
    // Parts as Arnold or Nuke write them: the beauty "rgba" DWAA, the AOV "diffuse" PIZ (bare R, G, B).
    const std::string input = dir.file("parted.####.exr");
    for (int frame = 1; frame <= kFrames; ++frame) {
        std::vector<OIIO::ImageSpec> specs{OIIO::ImageSpec(kWidth, kHeight, 4, OIIO::TypeHalf),
                                           OIIO::ImageSpec(kWidth, kHeight, 3, OIIO::TypeHalf)};
        specs[0].channelnames = {"R", "G", "B", "A"};
        specs[0].alpha_channel = 3;
        specs[0].attribute("oiio:subimagename", "rgba");
        specs[0].attribute("compression", "dwaa");
        specs[1].channelnames = {"R", "G", "B"};
        specs[1].attribute("oiio:subimagename", "diffuse");
        specs[1].attribute("compression", "piz");
        const std::string path = frame_file(input, frame);
        auto output = OIIO::ImageOutput::create(path);
        REQUIRE_MESSAGE((output && output->open(path, 2, specs.data())), OIIO::geterror());
        for (int part = 0; part < 2; ++part) {
            if (part > 0)
                REQUIRE(output->open(path, specs[part], OIIO::ImageOutput::AppendSubimage));
            std::vector<float> pixels;
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int c = 0; c < specs[part].nchannels; ++c)
                        pixels.push_back(pixel_value(frame, x, y, c + 4 * part));
            REQUIRE(output->write_image(OIIO::TypeFloat, pixels.data()));
        }
        REQUIRE(output->close());
    }
    const std::string copied = dir.file("out/copied.####.exr"), only = dir.file("out/only.####.exr");
    for (const auto& [output, options] : {std::pair{copied, ""}, {only, " --only-denoised"}}) {
        const testkit::CliResult result = run_modestack(
            "denoise " + input + " --layer diffuse --no-update-beauty -q" + options + " -o " + output);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::vector<PartInfo> parts = read_parts(frame_file(copied, frame));
        REQUIRE(parts.size() == 2);
        CHECK(parts[0].name == "rgba");
        CHECK(parts[0].compression == "zip"); // DWAA in: written lossless
        CHECK(parts[1].name == "diffuse");
        CHECK(parts[1].compression == "piz"); // lossless in: as it was
        // The beauty part's decoded values, unchanged (OIIO reads part 0 by default).
        const std::vector<std::string> rgba{"R", "G", "B", "A"};
        CHECK(testkit::read_channels(frame_file(copied, frame), rgba) ==
              testkit::read_channels(frame_file(input, frame), rgba));

        const std::vector<PartInfo> only_parts = read_parts(frame_file(only, frame));
        REQUIRE(only_parts.size() == 1);
        CHECK(only_parts[0].name == "diffuse");
        CHECK(only_parts[0].compression == "piz");
        // A single part left: a single-part file, its channels named by their layer.
        CHECK(std::set<std::string>(only_parts[0].channels.begin(), only_parts[0].channels.end()) ==
              std::set<std::string>{"diffuse.R", "diffuse.G", "diffuse.B", "diffuse.sigma.R",
                                    "diffuse.sigma.G", "diffuse.sigma.B"});
    }
    // Read back by modestack, the single part is still the layer "diffuse", with the values of the full
    // output.
    const std::string summary = dir.file("compare.json");
    const testkit::CliResult compare =
        run_modestack("compare " + only + " " + copied + " --layer diffuse -q --json " + summary);
    REQUIRE_MESSAGE(compare.exit_code == 0, compare.err);
    const nlohmann::json frames = nlohmann::json::parse(testkit::read_text(summary))["per_frame"];
    REQUIRE(frames.size() == kFrames);
    for (const auto& frame : frames)
        CHECK(frame["relative_mse"].get<double>() == 0.0);
}

TEST_CASE("denoise output options: a bad --compression or --data-type is a usage error of one line")
{
    TempDir dir;
    const std::string input = write_shot(dir, "in", "zip");
    for (const auto& [option, value] : {std::pair{"--compression", "lzw"},
                                        {"--compression", "dwaa:"},
                                        {"--compression", "zip:4"},
                                        {"--data-type", "double"}}) {
        CAPTURE(value);
        const testkit::CliResult result =
            denoise(input, dir.file("out/bad.####.exr"), std::string(option) + " " + value);
        CHECK(result.exit_code == 2);
        CHECK(std::count(result.err.begin(), result.err.end(), '\n') == 1);
        CHECK(result.err.find(option) != std::string::npos);
        CHECK(result.err.find(std::string("'") + value + "'") != std::string::npos);
        CHECK(!std::filesystem::exists(dir.file("out/bad.0001.exr")));
    }
}

TEST_CASE(
    "denoise --stage write takes the output options alone: the other tasks' files still fit, the same frames")
{
    TempDir dir;
    const std::string input = write_shot(dir, "in", "zip") + " --layer diffuse -q";
    const std::string job = dir.file("job/");
    for (const std::string& task :
         {" --stage stats --rows 1/1 -o " + job + "1.stats",
          " --stage solve --stats " + job + "1.stats -o " + job + "shot.solve",
          " --stage survey --solve " + job + "shot.solve --rows 1/1 -o " + job + "1.survey",
          " --stage modes --solve " + job + "shot.solve --survey " + job + "1.survey --rows 1/1 -o " + job +
              "1.modes"}) {
        const testkit::CliResult result = run_modestack("denoise " + input + task);
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    const std::string options = " --compression piz --data-type float --only-denoised";
    const std::string farm = dir.file("farm/d.####.exr"), single = dir.file("single/d.####.exr");
    const testkit::CliResult write =
        run_modestack("denoise " + input + " --stage write --solve " + job + "shot.solve --survey " + job +
                      "1.survey --modes " + job + "1.modes --frames 1/1" + options + " -o " + farm);
    REQUIRE_MESSAGE(write.exit_code == 0, write.err);
    const testkit::CliResult whole = run_modestack("denoise " + input + options + " -o " + single);
    REQUIRE_MESSAGE(whole.exit_code == 0, whole.err);
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const PartInfo part = read_parts(frame_file(farm, frame))[0];
        CHECK(part.compression == "piz");
        CHECK(part.channels.size() == 6);
        CHECK(type_of(part, "diffuse.R") == "float");
        CHECK(testkit::read_native(frame_file(farm, frame)) ==
              testkit::read_native(frame_file(single, frame)));
    }
}
