// End-to-end: `modestack denoise --update-beauty` (the default where the renderer
// conventions compose the beauty) on shots rendered by `modestack render`: after
// denoising DiffInd the beauty equals DiffCol × (DiffDir + DiffInd) + Emit of the
// output's own channels to half precision, its alpha is untouched and its sigma
// is DiffCol × DiffInd's; --no-update-beauty copies it bit for bit; an
// Arnold-style shot (the same light, multiplied by its colour, under Arnold's
// names) keeps RGBA = Σ of its light AOVs; a light counted twice or a renderer
// whose beauty is unknown leaves the beauty alone and the JSON says why; threads,
// streaming and farm stages give the same bits; two chained single-layer runs
// (DiffInd, then DiffDir on the first's output) keep the beauty the composite
// of its AOVs and combine its sigma in quadrature in its one set of channels;
// and a Cycles shot, if present.
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kFrames = 8;

nlohmann::json load_json(const std::string& path)
{
    return nlohmann::json::parse(testkit::read_text(path));
}

std::string frame_file(const std::string& base, int frame)
{
    return fmt::format("{}.{:04d}.exr", base, frame);
}

void run_ok(const std::string& arguments)
{
    auto result = run_modestack(arguments);
    REQUIRE_MESSAGE(result.exit_code == 0, arguments << "\n" << result.err);
}

std::string render_own_shot(const TempDir& dir)
{
    run_ok(fmt::format("render --scene orbit --frames 1-{} --spp 2 --size 48x36 -q -o {}", kFrames,
                       dir.file("own.####.exr")));
    return dir.file("own.####.exr");
}

std::vector<float> rgb(const std::string& file, const std::string& layer)
{
    const std::string prefix = layer.empty() ? "" : layer + ".";
    return testkit::read_channels(file, {prefix + "R", prefix + "G", prefix + "B"});
}

// |a - b| within a few half-float roundings of the terms' size.
bool within_half(double a, double b, double scale)
{
    return std::abs(a - b) <= 4.0 / 2048.0 * scale + 1e-6;
}

// Every pixel of every frame: beauty == Σ colour × layer of the file's own channels, to half precision
// of the values involved: the terms, and the input beauties (`input_bases`: the render, the
// outputs of earlier runs) the updates started from, whose rounding each keeps (a firefly's
// beauty of 1.0 rounds by 2^-11). `terms` are (colour layer or "", light layer).
void check_composite(const std::string& base, const std::string& beauty,
                     const std::vector<std::pair<std::string, std::string>>& terms,
                     const std::vector<std::string>& input_bases = {})
{
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string file = frame_file(base, frame);
        const std::vector<float> beauty_values = rgb(file, beauty);
        std::vector<float> input_scale(beauty_values.size(), 0.0f);
        for (const std::string& input_base : input_bases) {
            const std::vector<float> input = rgb(frame_file(input_base, frame), beauty);
            for (size_t i = 0; i < input.size(); ++i)
                input_scale[i] = std::max(input_scale[i], std::abs(input[i]));
        }
        std::vector<double> sum(beauty_values.size(), 0.0), scale(beauty_values.size(), 0.0);
        for (const auto& [colour, layer] : terms) {
            const std::vector<float> light = rgb(file, layer);
            const std::vector<float> colours =
                colour.empty() ? std::vector<float>(light.size(), 1.0f) : rgb(file, colour);
            for (size_t i = 0; i < sum.size(); ++i) {
                sum[i] += static_cast<double>(colours[i]) * light[i];
                scale[i] += std::abs(static_cast<double>(colours[i]) * light[i]);
            }
        }
        size_t off = 0;
        for (size_t i = 0; i < sum.size(); ++i)
            if (!within_half(
                    beauty_values[i], sum[i],
                    std::max({scale[i], std::abs(sum[i]), std::abs(static_cast<double>(input_scale[i]))}))) {
                if (off == 0)
                    MESSAGE("pixel value " << i << ": beauty " << beauty_values[i] << ", sum " << sum[i]);
                ++off;
            }
        CAPTURE(file);
        CHECK(off == 0);
    }
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && !a.empty() &&
           std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Every output frame of two runs holds the same channels and bytes.
void check_same_outputs(const std::string& a, const std::string& b)
{
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        CHECK(testkit::read_channel_names(frame_file(a, frame)) ==
              testkit::read_channel_names(frame_file(b, frame)));
        CHECK(testkit::read_native(frame_file(a, frame)) == testkit::read_native(frame_file(b, frame)));
    }
}

// One layer of a restyled shot: its name ("" = the bare R, G, B, A), components, and
// each component's value from the own frame (`at(channel)`).
struct StyledLayer {
    std::string name;
    std::vector<std::string> components;
    std::function<float(const std::function<float(const std::string&)>& at, const std::string& component)>
        value;
};

// A copy of each frame of the own shot, dir/<style>.####.exr, made of `layers` (half) with `attribute` set.
void write_styled_shot(const TempDir& dir, const std::string& style, const std::vector<StyledLayer>& layers,
                       const std::pair<std::string, std::string>& attribute)
{
    for (int frame = 1; frame <= kFrames; ++frame) {
        auto input = OIIO::ImageInput::open(dir.file(fmt::format("own.{:04d}.exr", frame)));
        REQUIRE(input);
        const OIIO::ImageSpec& spec = input->spec();
        std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
        REQUIRE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, pixels.data()));
        std::vector<std::string> names;
        for (const StyledLayer& layer : layers)
            for (const std::string& c : layer.components)
                names.push_back(layer.name.empty() ? c : layer.name + "." + c);
        OIIO::ImageSpec out(spec.width, spec.height, static_cast<int>(names.size()), OIIO::TypeHalf);
        out.channelnames = names;
        out.alpha_channel = -1;
        out.attribute("compression", "zip");
        out.attribute(attribute.first, attribute.second);
        std::vector<float> values;
        for (size_t p = 0; p < static_cast<size_t>(spec.width) * spec.height; ++p) {
            auto at = [&](const std::string& channel) {
                return pixels[p * spec.nchannels + static_cast<size_t>(spec.channelindex(channel))];
            };
            for (const StyledLayer& layer : layers)
                for (const std::string& c : layer.components)
                    values.push_back(layer.value(at, c));
        }
        const std::string to = dir.file(fmt::format("{}.{:04d}.exr", style, frame));
        auto output = OIIO::ImageOutput::create(to);
        REQUIRE(output);
        REQUIRE(output->open(to, out));
        REQUIRE(output->write_image(OIIO::TypeFloat, values.data()));
        REQUIRE(output->close());
    }
}

using At = std::function<float(const std::string&)>;
const std::vector<std::string> kRgb{"R", "G", "B"};
float beauty_of(const At& at, const std::string& c)
{
    return at("Combined." + c);
}
float albedo(const At& at, const std::string& c)
{
    return at("DiffCol." + c);
}
float direct(const At& at, const std::string& c)
{
    return at("DiffCol." + c) * at("DiffDir." + c);
}
float indirect(const At& at, const std::string& c)
{
    return at("DiffCol." + c) * at("DiffInd." + c);
}
float raw_indirect(const At& at, const std::string& c)
{
    return at("DiffInd." + c);
}
float emission(const At& at, const std::string& c)
{
    return at("Emit." + c);
}

// The own shot as Arnold writes its AOVs: the light already multiplied by its colour
// (diffuse_direct = DiffCol × DiffDir), a combined `diffuse`, the beauty bare RGBA.
void write_arnold_shot(const TempDir& dir)
{
    write_styled_shot(
        dir, "arnold",
        {{"", {"R", "G", "B", "A"}, beauty_of},
         {"diffuse_albedo", kRgb, albedo},
         {"diffuse_direct", kRgb, direct},
         {"diffuse_indirect", kRgb, indirect},
         {"emission", kRgb, emission},
         {"diffuse", kRgb,
          [](const At& at, const std::string& c) { return direct(at, c) + indirect(at, c); }},
         {"diffuse_indirect_variance", kRgb,
          [](const At& at, const std::string& c) {
              return at("DiffCol." + c) * at("DiffCol." + c) * at("DiffIndVar." + c);
          }},
         {"N", {"X", "Y", "Z"}, [](const At& at, const std::string& c) { return at("Normal." + c); }},
         {"", {"Z"}, [](const At& at, const std::string&) { return at("Depth.Z"); }}},
        {"arnold/version", "Arnold 7.2.1.0"});
}

} // namespace

TEST_CASE("denoise --layer DiffInd keeps the beauty Combined = DiffCol x (DiffDir + DiffInd) + Emit, "
          "--no-update-beauty copies it bit for bit")
{
    TempDir dir;
    const std::string input = render_own_shot(dir);
    const std::vector<std::pair<std::string, std::string>> terms{
        {"DiffCol", "DiffDir"}, {"DiffCol", "DiffInd"}, {"", "Emit"}};
    check_composite(dir.file("own"), "Combined", terms); // the renderer's own promise (core/render/aov.h)

    run_ok(fmt::format("denoise {} --layer DiffInd -q -o {} --json {}", input, dir.file("on/d.####.exr"),
                       dir.file("on.json")));
    const nlohmann::json on = load_json(dir.file("on.json"));
    CHECK(on["beauty"]["updated"] == true);
    CHECK(on["beauty"]["requested"] == "auto");
    CHECK(on["beauty"]["layer"] == "Combined");
    CHECK(on["beauty"]["formula"] == "Combined += DiffCol * (denoised - noisy DiffInd)");
    CHECK(on["beauty"]["sigma"]["channels"] ==
          nlohmann::json::array({"Combined.sigma.R", "Combined.sigma.G", "Combined.sigma.B"}));
    check_composite(dir.file("on/d"), "Combined", terms, {dir.file("own")});

    size_t changed = 0;
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string in = frame_file(dir.file("own"), frame), out = frame_file(dir.file("on/d"), frame);
        const std::vector<float> before = rgb(in, "Combined"), after = rgb(out, "Combined");
        for (size_t i = 0; i < before.size(); ++i)
            changed += before[i] != after[i];
        CHECK(same_bits(testkit::read_channels(in, {"Combined.A"}),
                        testkit::read_channels(out, {"Combined.A"})));
        // The beauty's sigma is DiffCol × DiffInd's.
        const std::vector<float> sigma = rgb(out, "Combined.sigma"), layer_sigma = rgb(out, "DiffInd.sigma"),
                                 colour = rgb(out, "DiffCol");
        for (size_t i = 0; i < sigma.size(); ++i)
            CHECK(within_half(sigma[i], static_cast<double>(colour[i]) * layer_sigma[i], std::abs(sigma[i])));
    }
    CHECK(changed > 0); // denoising moved the beauty: the check above is not the input's

    run_ok(fmt::format("denoise {} --layer DiffInd --no-update-beauty -q -o {} --json {}", input,
                       dir.file("off/d.####.exr"), dir.file("off.json")));
    const nlohmann::json off = load_json(dir.file("off.json"));
    CHECK(off["beauty"]["updated"] == false);
    CHECK(off["beauty"]["reason"] == "--no-update-beauty");
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::vector<std::string> beauty{"Combined.R", "Combined.G", "Combined.B", "Combined.A"};
        CHECK(same_bits(testkit::read_channels(frame_file(dir.file("own"), frame), beauty),
                        testkit::read_channels(frame_file(dir.file("off/d"), frame), beauty)));
        const std::vector<std::string> names =
            testkit::read_channel_names(frame_file(dir.file("off/d"), frame));
        CHECK(std::find(names.begin(), names.end(), "Combined.sigma.R") == names.end());
    }
    // The denoised layer is the same either way.
    CHECK(same_bits(rgb(frame_file(dir.file("on/d"), 3), "DiffInd"),
                    rgb(frame_file(dir.file("off/d"), 3), "DiffInd")));

    auto both =
        run_modestack(fmt::format("denoise {} --layer DiffInd --update-beauty --no-update-beauty -q -o {}",
                                  input, dir.file("both/d.####.exr")));
    CHECK(both.exit_code == 2);
}

TEST_CASE("denoise --update-beauty chained: a denoise output denoised again for another layer keeps the "
          "beauty the composite of its AOVs, its sigma the quadrature of both layers' terms")
{
    TempDir dir;
    const std::string input = render_own_shot(dir);
    run_ok(fmt::format("denoise {} --layer DiffInd -q -o {}", input, dir.file("first/d.####.exr")));
    run_ok(fmt::format("denoise {} --layer DiffDir -q -o {} --json {}", dir.file("first/d.####.exr"),
                       dir.file("second/d.####.exr"), dir.file("second.json")));
    const nlohmann::json second = load_json(dir.file("second.json"));
    CHECK(second["beauty"]["updated"] == true);
    CHECK(second["beauty"]["formula"] == "Combined += DiffCol * (denoised - noisy DiffDir)");
    CHECK(second["beauty"]["sigma"]["rewritten"] == true);
    CHECK(second["beauty"]["sigma"]["channels"] ==
          nlohmann::json::array({"Combined.sigma.R", "Combined.sigma.G", "Combined.sigma.B"}));
    CHECK(second["beauty"]["sigma"]["formula"] ==
          "sqrt(Combined.sigma (input)^2 + DiffCol^2 * DiffDir.sigma^2)");
    check_composite(dir.file("second/d"), "Combined",
                    {{"DiffCol", "DiffDir"}, {"DiffCol", "DiffInd"}, {"", "Emit"}},
                    {dir.file("own"), dir.file("first/d")});

    size_t moved = 0;
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string first = frame_file(dir.file("first/d"), frame),
                          out = frame_file(dir.file("second/d"), frame);
        CAPTURE(out);
        // One set of the beauty's sigma channels, every name once.
        std::vector<std::string> names = testkit::read_channel_names(out);
        CHECK(std::count(names.begin(), names.end(), "Combined.sigma.R") == 1);
        CHECK(std::count_if(names.begin(), names.end(), [](const std::string& name) {
                  return name.find("sigma") != std::string::npos;
              }) == 9);
        std::sort(names.begin(), names.end());
        CHECK(std::adjacent_find(names.begin(), names.end()) == names.end());
        // sigma = sqrt((DiffCol σ_DiffInd)² + (DiffCol σ_DiffDir)²), the first run's term kept.
        const std::vector<float> sigma = rgb(out, "Combined.sigma"), colour = rgb(out, "DiffCol"),
                                 indirect = rgb(out, "DiffInd.sigma"), direct = rgb(out, "DiffDir.sigma"),
                                 before = rgb(first, "Combined.sigma");
        size_t off = 0;
        for (size_t i = 0; i < sigma.size(); ++i) {
            const double expected = std::hypot(static_cast<double>(colour[i]) * indirect[i],
                                               static_cast<double>(colour[i]) * direct[i]);
            off += !within_half(sigma[i], expected, std::max(expected, static_cast<double>(sigma[i])));
            moved += sigma[i] != before[i];
        }
        CHECK(off == 0);
    }
    CHECK(moved > 0); // the second run's term is in: the check above is not the first run's sigma

    // --only-denoised keeps the rewritten beauty sigma, once.
    run_ok(fmt::format("denoise {} --layer DiffDir --only-denoised -q -o {}", dir.file("first/d.####.exr"),
                       dir.file("only/d.####.exr")));
    const std::vector<std::string> only = testkit::read_channel_names(frame_file(dir.file("only/d"), 2));
    CHECK(std::count(only.begin(), only.end(), "Combined.sigma.G") == 1);
    CHECK(std::count(only.begin(), only.end(), "DiffInd.sigma.G") == 0);
    CHECK(same_bits(rgb(frame_file(dir.file("only/d"), 2), "Combined.sigma"),
                    rgb(frame_file(dir.file("second/d"), 2), "Combined.sigma")));
}

TEST_CASE("denoise --update-beauty: threads, a streamed run and farm stages write the same bits")
{
    TempDir dir;
    // Tall enough (600 rows) to stream in bands and to split into farm tasks of 64-row blocks.
    run_ok(fmt::format("render --scene orbit --frames 1-{} --spp 1 --size 32x600 -q -o {}", kFrames,
                       dir.file("own.####.exr")));
    const std::string denoise = fmt::format("denoise {} --layer DiffInd -q ", dir.file("own.####.exr"));
    run_ok(denoise + "--threads 1 -o " + dir.file("t1/d.####.exr") + " --json " + dir.file("t1.json"));
    run_ok(denoise + "--threads 2 -o " + dir.file("t2/d.####.exr"));
    CHECK(load_json(dir.file("t1.json"))["beauty"]["updated"] == true);
    check_same_outputs(dir.file("t1/d"), dir.file("t2/d"));

    // Kept and streamed (as test_denoise_cli: without the mode filter, the budget what the
    // kept run's program and files held plus 2.3 MB). The plan needs 1.83 MB for a streamed
    // 16-row band and 2.82 MB to keep the shot; 2.3 MB lies halfway, because the program's
    // resident size, which --max-memory counts too, differs by a few 100 KB between runs.
    run_ok(denoise + "--no-mode-filter -o " + dir.file("kept/d.####.exr") + " --json " +
           dir.file("kept.json"));
    const nlohmann::json kept = load_json(dir.file("kept.json"));
    CHECK(kept["in_memory"] == true);
    // Under heavy load the resident size of a run has come out more than 0.5 MB below the kept
    // run's, so that the shot fit: then the budget is lowered by 0.3 MB and the run repeated
    // (lower is safe: the program came out smaller, so the band fits all the more).
    std::int64_t budget = kept["memory_held_bytes"].get<std::int64_t>() + 2'300'000;
    nlohmann::json streamed;
    std::string streamed_dir;
    for (int attempt = 1; attempt <= 3; ++attempt, budget -= 300'000) {
        streamed_dir = dir.file("streamed" + std::to_string(attempt));
        run_ok(denoise + fmt::format("--no-mode-filter --max-memory {} -o {}/d.####.exr --json {}.json",
                                     budget, streamed_dir, streamed_dir));
        streamed = load_json(streamed_dir + ".json");
        if (streamed["in_memory"] == false)
            break;
    }
    CHECK(streamed["in_memory"] == false);
    CHECK(streamed["beauty"]["updated"] == true);
    check_same_outputs(dir.file("kept/d"), streamed_dir + "/d");

    // The farm: statistics, solve, survey, modes, then two write tasks.
    run_ok(denoise + "--stage stats --rows 1/2 -o " + dir.file("s1.stats"));
    run_ok(denoise + "--stage stats --rows 2/2 -o " + dir.file("s2.stats"));
    run_ok(denoise + "--stage solve --stats " + dir.file("s1.stats") + " " + dir.file("s2.stats") + " -o " +
           dir.file("shot.solve"));
    const std::string solved = denoise + "--solve " + dir.file("shot.solve") + " ";
    run_ok(solved + "--stage survey --rows 1/1 -o " + dir.file("1.survey"));
    const std::string surveyed = solved + "--survey " + dir.file("1.survey") + " ";
    run_ok(surveyed + "--stage modes --rows 1/1 -o " + dir.file("1.modes"));
    const std::string write = surveyed + "--stage write --modes " + dir.file("1.modes");
    run_ok(write + " --frames 1/2 -o " + dir.file("farm/d.####.exr"));
    run_ok(write + " --frames 2/2 -o " + dir.file("farm/d.####.exr"));
    check_same_outputs(dir.file("t1/d"), dir.file("farm/d"));
}

TEST_CASE("denoise --update-beauty on an Arnold-style shot: RGBA = the sum of its light AOVs, a light "
          "counted twice or an unknown renderer leaves the beauty alone and says why")
{
    TempDir dir;
    const std::string own = render_own_shot(dir);
    write_arnold_shot(dir);
    const std::string input = dir.file("arnold.####.exr");
    const std::vector<std::pair<std::string, std::string>> terms{
        {"", "diffuse_direct"}, {"", "diffuse_indirect"}, {"", "emission"}};
    check_composite(dir.file("arnold"), "", terms);

    run_ok(fmt::format("denoise {} --layer diffuse_indirect -q -o {} --json {}", input,
                       dir.file("on/d.####.exr"), dir.file("on.json")));
    const nlohmann::json on = load_json(dir.file("on.json"));
    CHECK(on["renderer"]["name"] == "arnold");
    CHECK(on["beauty"]["updated"] == true);
    CHECK(on["beauty"]["layer"] == "");
    CHECK(on["beauty"]["formula"] == "the unnamed R, G, B += (denoised - noisy diffuse_indirect)");
    CHECK(on["beauty"]["sigma"]["channels"] == nlohmann::json::array({"sigma.R", "sigma.G", "sigma.B"}));
    check_composite(dir.file("on/d"), "", terms, {dir.file("arnold")});
    CHECK(!same_bits(rgb(frame_file(dir.file("arnold"), 2), ""), rgb(frame_file(dir.file("on/d"), 2), "")));

    // The combined `diffuse` holds diffuse_indirect's light too: denoised together, the beauty would count it
    // twice.
    run_ok(fmt::format("denoise {} --layer diffuse --layer diffuse_indirect -q -o {} --json {}", input,
                       dir.file("twice/d.####.exr"), dir.file("twice.json")));
    const nlohmann::json twice = load_json(dir.file("twice.json"));
    CHECK(twice["beauty"]["updated"] == false);
    CHECK_MESSAGE(twice["beauty"]["reason"].get<std::string>().find("count that light twice") !=
                      std::string::npos,
                  twice["beauty"].dump());
    CHECK(same_bits(testkit::read_channels(frame_file(dir.file("arnold"), 4), {"R", "G", "B", "A"}),
                    testkit::read_channels(frame_file(dir.file("twice/d"), 4), {"R", "G", "B", "A"})));
    auto refused =
        run_modestack(fmt::format("denoise {} --layer diffuse --layer diffuse_indirect --update-beauty "
                                  "-q -o {}",
                                  input, dir.file("refused/d.####.exr")));
    CHECK(refused.exit_code == 2);
    CHECK_MESSAGE(
        refused.err.find("--update-beauty: diffuse and diffuse_indirect both hold diffuse_indirect") !=
            std::string::npos,
        refused.err);
    // The combined layer alone stands for its parts.
    run_ok(fmt::format("denoise {} --layer diffuse -q -o {} --json {}", input,
                       dir.file("combined/d.####.exr"), dir.file("combined.json")));
    CHECK(load_json(dir.file("combined.json"))["beauty"]["updated"] == true);

    // The own shot read under another renderer's conventions: no composition, beauty untouched.
    run_ok(fmt::format("denoise {} --layer DiffInd --renderer vray -q -o {} --json {}", own,
                       dir.file("unknown/d.####.exr"), dir.file("unknown.json")));
    const nlohmann::json unknown = load_json(dir.file("unknown.json"));
    CHECK(unknown["beauty"]["updated"] == false);
    CHECK_MESSAGE(unknown["beauty"]["reason"].get<std::string>().find(
                      "DiffInd is not a light layer of the vray") != std::string::npos,
                  unknown["beauty"].dump());
    const std::vector<std::string> beauty{"Combined.R", "Combined.G", "Combined.B", "Combined.A"};
    CHECK(same_bits(testkit::read_channels(frame_file(dir.file("own"), 5), beauty),
                    testkit::read_channels(frame_file(dir.file("unknown/d"), 5), beauty)));
    auto asked =
        run_modestack(fmt::format("denoise {} --layer DiffInd --renderer vray --update-beauty -q -o {}", own,
                                  dir.file("asked/d.####.exr")));
    CHECK(asked.exit_code == 2);
    CHECK_MESSAGE(asked.err.find("--update-beauty: DiffInd is not a light layer") != std::string::npos,
                  asked.err);
}

TEST_CASE("denoise --update-beauty on the Cycles shot: Combined moves by DiffCol x the change of DiffInd")
{
    const std::string shot = "/work/shared/cycles/spin_room/spp4";
    if (!std::filesystem::exists(shot + "/frame.0001.exr")) {
        testkit::report_skipped("the Cycles shot " + shot + " is not on this machine");
        return;
    }
    TempDir dir;
    run_ok(fmt::format("denoise {}/frame.####.exr --frames 1-{} --layer DiffInd -q -o {} --json {}", shot,
                       kFrames, dir.file("d.####.exr"), dir.file("on.json")));
    const nlohmann::json on = load_json(dir.file("on.json"));
    CHECK(on["renderer"]["name"] == "cycles");
    CHECK(on["beauty"]["formula"] ==
          "ViewLayer.Combined += ViewLayer.DiffCol * (denoised - noisy ViewLayer.DiffInd)");
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string in = fmt::format("{}/frame.{:04d}.exr", shot, frame),
                          out = frame_file(dir.file("d"), frame);
        const std::vector<float> beauty_in = rgb(in, "ViewLayer.Combined"),
                                 beauty_out = rgb(out, "ViewLayer.Combined");
        const std::vector<float> layer_in = rgb(in, "ViewLayer.DiffInd"),
                                 layer_out = rgb(out, "ViewLayer.DiffInd");
        const std::vector<float> colour = rgb(out, "ViewLayer.DiffCol");
        size_t off = 0;
        for (size_t i = 0; i < beauty_in.size(); ++i) {
            const double expected =
                beauty_in[i] + static_cast<double>(colour[i]) * (layer_out[i] - layer_in[i]);
            off += !within_half(beauty_out[i], expected, std::abs(expected));
        }
        CAPTURE(frame);
        CHECK(off == 0);
    }
}

TEST_CASE("denoise --update-beauty on a V-Ray-style raw layer: the beauty and the product AOV move by the "
          "diffuse filter x the change")
{
    TempDir dir;
    render_own_shot(dir);
    write_styled_shot(dir, "vray",
                      {{"", {"R", "G", "B", "A"}, beauty_of},
                       {"VRayDiffuseFilter", kRgb, albedo},
                       {"VRayLighting", kRgb, direct},
                       {"VRayRawGlobalIllumination", kRgb, raw_indirect},
                       {"VRayGlobalIllumination", kRgb, indirect},
                       {"VRaySelfIllumination", kRgb, emission}},
                      {"vray/version", "V-Ray 6"});
    run_ok(fmt::format("denoise {} --layer VRayRawGlobalIllumination -q -o {} --json {}",
                       dir.file("vray.####.exr"), dir.file("on/d.####.exr"), dir.file("on.json")));
    const nlohmann::json on = load_json(dir.file("on.json"));
    CHECK(on["renderer"]["name"] == "vray");
    CHECK(on["beauty"]["updated"] == true);
    CHECK(on["beauty"]["formula"] ==
          "the unnamed R, G, B += VRayDiffuseFilter * (denoised - noisy VRayRawGlobalIllumination)");
    CHECK(on["beauty"]["products"][0]["layer"] == "VRayGlobalIllumination");
    check_composite(dir.file("on/d"), "",
                    {{"", "VRayLighting"}, {"", "VRayGlobalIllumination"}, {"", "VRaySelfIllumination"}},
                    {dir.file("vray")});
    check_composite(dir.file("on/d"), "VRayGlobalIllumination",
                    {{"VRayDiffuseFilter", "VRayRawGlobalIllumination"}}, {dir.file("vray")});
    CHECK(!same_bits(rgb(frame_file(dir.file("vray"), 2), "VRayGlobalIllumination"),
                     rgb(frame_file(dir.file("on/d"), 2), "VRayGlobalIllumination")));
    // The raw layer and its product denoised together would count that light twice.
    run_ok(fmt::format(
        "denoise {} --layer VRayRawGlobalIllumination --layer VRayGlobalIllumination -q -o {} --json {}",
        dir.file("vray.####.exr"), dir.file("twice/d.####.exr"), dir.file("twice.json")));
    CHECK(load_json(dir.file("twice.json"))["beauty"]["updated"] == false);
}

TEST_CASE(
    "denoise --update-beauty finds Arnold's beauty under its alias RGBA, as a multi-part file names its part")
{
    TempDir dir;
    render_own_shot(dir);
    write_styled_shot(dir, "arnold_parts",
                      {{"RGBA", {"R", "G", "B", "A"}, beauty_of},
                       {"diffuse_albedo", kRgb, albedo},
                       {"diffuse_direct", kRgb, direct},
                       {"diffuse_indirect", kRgb, indirect},
                       {"emission", kRgb, emission}},
                      {"arnold/version", "Arnold 7.2.1.0"});
    const std::vector<std::pair<std::string, std::string>> terms{
        {"", "diffuse_direct"}, {"", "diffuse_indirect"}, {"", "emission"}};
    check_composite(dir.file("arnold_parts"), "RGBA", terms);
    run_ok(fmt::format("denoise {} --layer diffuse_indirect -q -o {} --json {}",
                       dir.file("arnold_parts.####.exr"), dir.file("on/d.####.exr"), dir.file("on.json")));
    const nlohmann::json on = load_json(dir.file("on.json"));
    CHECK(on["renderer"]["name"] == "arnold");
    CHECK(on["beauty"]["updated"] == true);
    CHECK(on["beauty"]["layer"] == "RGBA");
    CHECK(on["beauty"]["sigma"]["channels"] ==
          nlohmann::json::array({"RGBA.sigma.R", "RGBA.sigma.G", "RGBA.sigma.B"}));
    check_composite(dir.file("on/d"), "RGBA", terms, {dir.file("arnold_parts")});
}
