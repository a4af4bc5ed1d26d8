// The renderer conventions table (app/renderer_conventions.h) end to end: one
// shot of our renderer, renamed channel by channel (OIIO) into Arnold-,
// RenderMan- and Karma-style shots, is denoised to the same pixels as the
// original with its guides and variance found under each renderer's names and
// the renderer detected; a guide --mode-filter-guides names that is missing
// exits 2 naming what was looked for, auto goes on without it; --renderer
// overrides detection; a bad --conventions file is one line naming it. The
// compiled-in table is the shipped file, and detection is checked on headers.
#include "app/renderer_conventions.h"
#include "app/renderer_detection.h"
#include "core/common/error.h"
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kFrames = 8;

nlohmann::json load_json(const std::string& path)
{
    return nlohmann::json::parse(testkit::read_text(path));
}

// Renders the shot every test renames: our renderer's orbit, small and noisy.
std::string render_own_shot(const TempDir& dir)
{
    auto rendered =
        run_modestack(fmt::format("render --scene orbit --frames 1-{} --spp 2 --size 48x36 -q -o {}", kFrames,
                                  dir.file("own.####.exr")));
    REQUIRE_MESSAGE(rendered.exit_code == 0, rendered.err);
    return dir.file("own.####.exr");
}

// Writes a copy of frame `from` named `to` with layers renamed as `names` says:
// "Layer" -> "new" gives new.<component>, -> "" the bare components (a beauty's
// R, G, B, A), -> "=name" the one channel `name`; other layers are left out.
// The modestack:* attributes are dropped and `attributes` added.
void rename_frame(const std::string& from, const std::string& to,
                  const std::map<std::string, std::string>& names,
                  const std::map<std::string, std::string>& attributes)
{
    auto input = OIIO::ImageInput::open(from);
    REQUIRE(input);
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<float> pixels(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    REQUIRE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, pixels.data()));
    std::vector<int> kept;
    std::vector<std::string> kept_names;
    for (int c = 0; c < spec.nchannels; ++c) {
        const std::string& channel = spec.channelnames[static_cast<size_t>(c)];
        const size_t dot = channel.rfind('.');
        auto renamed = names.find(channel.substr(0, dot));
        if (dot == std::string::npos || renamed == names.end())
            continue;
        kept.push_back(c);
        const std::string component = channel.substr(dot + 1);
        kept_names.push_back(renamed->second.empty()          ? component
                             : renamed->second.front() == '=' ? renamed->second.substr(1)
                                                              : renamed->second + "." + component);
    }
    OIIO::ImageSpec out(spec.width, spec.height, static_cast<int>(kept.size()), OIIO::TypeHalf);
    out.channelnames = kept_names;
    out.channelformats.clear();
    for (int c : kept)
        out.channelformats.push_back(spec.channelformat(c));
    out.alpha_channel = -1;
    out.attribute("compression", "zip");
    for (const auto& [name, value] : attributes)
        out.attribute(name, value);
    std::vector<float> out_pixels(static_cast<size_t>(spec.width) * spec.height * kept.size());
    for (size_t p = 0; p < static_cast<size_t>(spec.width) * spec.height; ++p)
        for (size_t k = 0; k < kept.size(); ++k)
            out_pixels[p * kept.size() + k] =
                pixels[p * static_cast<size_t>(spec.nchannels) + static_cast<size_t>(kept[k])];
    auto output = OIIO::ImageOutput::create(to);
    REQUIRE(output);
    REQUIRE(output->open(to, out));
    REQUIRE(output->write_image(OIIO::TypeFloat, out_pixels.data()));
    REQUIRE(output->close());
}

// A renamed copy of every frame of the own shot: dir/<name>.####.exr.
std::string rename_shot(const TempDir& dir, const std::string& name,
                        const std::map<std::string, std::string>& names,
                        const std::map<std::string, std::string>& attributes = {})
{
    for (int frame = 1; frame <= kFrames; ++frame)
        rename_frame(dir.file(fmt::format("own.{:04d}.exr", frame)),
                     dir.file(fmt::format("{}.{:04d}.exr", name, frame)), names, attributes);
    return dir.file(name + ".####.exr");
}

// Our renderer's layers under Arnold's, RenderMan's and Karma's names.
const std::map<std::string, std::string> kArnold{{"Combined", ""},
                                                 {"DiffDir", "diffuse_direct"},
                                                 {"DiffInd", "diffuse_indirect"},
                                                 {"DiffCol", "diffuse_albedo"},
                                                 {"Emit", "emission"},
                                                 {"Normal", "N"},
                                                 {"Depth", "=Z"},
                                                 {"Position", "P"},
                                                 {"DiffIndVar", "diffuse_indirect_variance"}};
const std::map<std::string, std::string> kRenderMan{{"Combined", "Ci"},
                                                    {"DiffDir", "directDiffuse"},
                                                    {"DiffInd", "indirectDiffuse"},
                                                    {"DiffCol", "albedo"},
                                                    {"Emit", "emissive"},
                                                    {"Normal", "normal"},
                                                    {"Depth", "=zfiltered"},
                                                    {"DiffIndVar", "indirectDiffuse_mse"}};
const std::map<std::string, std::string> kKarma{{"Combined", "C"},
                                                {"DiffDir", "directdiffuse"},
                                                {"DiffInd", "indirectdiffuse"},
                                                {"DiffCol", "albedo"},
                                                {"Emit", "directemission"},
                                                {"Normal", "N"},
                                                {"Depth", "=depth"},
                                                {"Position", "P"},
                                                {"DiffIndVar", "indirectdiffuse_variance"}};

// The denoised layer and its sigma of every frame <base>.NNNN.exr.
std::vector<float> denoised_values(const std::string& base, const std::string& layer)
{
    std::vector<float> all;
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string file = fmt::format("{}.{:04d}.exr", base, frame);
        for (const std::string& part : {layer, layer + ".sigma"}) {
            std::vector<float> values = testkit::read_channels(file, {part + ".R", part + ".G", part + ".B"});
            all.insert(all.end(), values.begin(), values.end());
        }
    }
    return all;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && !a.empty() &&
           std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

} // namespace

TEST_CASE("renderer conventions: Arnold-, RenderMan- and Karma-style renames of our shot denoise to the same "
          "pixels")
{
    TempDir dir;
    const std::string own = render_own_shot(dir);
    auto reference = run_modestack("denoise " + own + " --layer DiffInd -q --json " + dir.file("own.json") +
                                   " -o " + dir.file("own_den/d.####.exr"));
    REQUIRE_MESSAGE(reference.exit_code == 0, reference.err);
    const nlohmann::json own_json = load_json(dir.file("own.json"));
    CHECK(own_json["renderer"]["name"] == "modestack");
    CHECK(own_json["renderer"]["variance"]["found"] == "DiffIndVar");
    CHECK(own_json["mode_filter"]["feature_guides"] == nlohmann::json::array({"albedo", "normal", "depth"}));
    const std::vector<float> expected = denoised_values(dir.file("own_den/d"), "DiffInd");

    struct Case {
        std::string renderer, layer, detected_by, albedo, normal, depth, variance;
        std::map<std::string, std::string> names, attributes;
    };
    const Case cases[] = {
        {"arnold",
         "diffuse_indirect",
         "header attribute arnold/version",
         "diffuse_albedo",
         "N",
         "Z",
         "diffuse_indirect_variance",
         kArnold,
         {{"arnold/version", "Arnold 7.2.1.0"}}},
        {"renderman",
         "indirectDiffuse",
         "layers Ci, directDiffuse, indirectDiffuse",
         "albedo",
         "normal",
         "zfiltered",
         "indirectDiffuse_mse",
         kRenderMan,
         {}},
        {"karma",
         "indirectdiffuse",
         "layers directdiffuse, indirectdiffuse",
         "albedo",
         "N",
         "depth",
         "indirectdiffuse_variance",
         kKarma,
         {}},
    };
    for (const Case& style : cases) {
        CAPTURE(style.renderer);
        const std::string input = rename_shot(dir, style.renderer, style.names, style.attributes);
        const std::string json = dir.file(style.renderer + ".json");
        auto run = run_modestack("denoise " + input + " --layer " + style.layer + " -q --json " + json +
                                 " -o " + dir.file(style.renderer + "_den/d.####.exr"));
        REQUIRE_MESSAGE(run.exit_code == 0, run.err);
        const nlohmann::json summary = load_json(json);
        const nlohmann::json& renderer = summary["renderer"];
        CHECK(renderer["name"] == style.renderer);
        CHECK(renderer["detected_by"] == style.detected_by);
        CHECK(renderer["conventions"] == "built-in");
        CHECK(renderer["guides"]["albedo"]["found"] == style.albedo);
        CHECK(renderer["guides"]["normal"]["found"] == style.normal);
        CHECK(renderer["guides"]["depth"]["found"] == style.depth);
        CHECK(renderer["variance"]["found"] == style.variance);
        CHECK(summary["mode_filter"]["feature_guides"] == own_json["mode_filter"]["feature_guides"]);
        CHECK(summary["rank"]["n"] == own_json["rank"]["n"]);
        CHECK(same_bits(denoised_values(dir.file(style.renderer + "_den/d"), style.layer), expected));
    }
}

TEST_CASE(
    "renderer conventions: a guide --mode-filter-guides names is an error when missing, auto goes without it")
{
    TempDir dir;
    render_own_shot(dir);
    std::map<std::string, std::string> no_normal = kArnold;
    no_normal.erase("Normal");
    const std::string input = rename_shot(dir, "arnold", no_normal, {{"arnold/version", "Arnold 7.2.1.0"}});
    auto refused = run_modestack("denoise " + input +
                                 " --layer diffuse_indirect -q --mode-filter-guides albedo,normal -o " +
                                 dir.file("refused/d.####.exr"));
    CHECK(refused.exit_code == 2);
    CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
    CHECK_MESSAGE(refused.err.find("--mode-filter-guides normal") != std::string::npos, refused.err);
    CHECK_MESSAGE(refused.err.find("looked for N, N_noice") != std::string::npos, refused.err);
    CHECK_MESSAGE(refused.err.find("arnold.0001.exr") != std::string::npos, refused.err);
    CHECK_FALSE(std::ifstream(dir.file("refused/d.0001.exr")).good());

    auto automatic = run_modestack("denoise " + input + " --layer diffuse_indirect -q --json " +
                                   dir.file("auto.json") + " -o " + dir.file("auto/d.####.exr"));
    REQUIRE_MESSAGE(automatic.exit_code == 0, automatic.err);
    const nlohmann::json summary = load_json(dir.file("auto.json"));
    CHECK(summary["mode_filter"]["feature_guides"] == nlohmann::json::array({"albedo", "depth"}));
    CHECK(summary["renderer"]["guides"]["normal"]["found"].is_null());
    CHECK(summary["renderer"]["guides"]["normal"]["looked_for"] == nlohmann::json::array({"N", "N_noice"}));
}

TEST_CASE("renderer conventions: --renderer overrides detection, takes aliases and refuses unknown names")
{
    TempDir dir;
    render_own_shot(dir);
    const std::string input = rename_shot(dir, "renderman", kRenderMan);
    const std::string denoise = "denoise " + input + " --layer indirectDiffuse -q ";
    auto alias = run_modestack(denoise + "--renderer prman --json " + dir.file("prman.json") + " -o " +
                               dir.file("prman/d.####.exr"));
    REQUIRE_MESSAGE(alias.exit_code == 0, alias.err);
    CHECK(load_json(dir.file("prman.json"))["renderer"]["name"] == "renderman");
    CHECK(load_json(dir.file("prman.json"))["renderer"]["detected_by"] == "--renderer prman");

    // Read as a Cycles shot, none of its guides or its variance is found.
    auto cycles = run_modestack(denoise + "--renderer cycles --json " + dir.file("cycles.json") + " -o " +
                                dir.file("cycles/d.####.exr"));
    REQUIRE_MESSAGE(cycles.exit_code == 0, cycles.err);
    const nlohmann::json summary = load_json(dir.file("cycles.json"));
    CHECK(summary["renderer"]["name"] == "cycles");
    CHECK(summary["renderer"]["guides"]["albedo"]["looked_for"] ==
          nlohmann::json::array({"DiffCol", "Denoising Albedo"}));
    CHECK(summary["renderer"]["variance"]["found"].is_null());
    CHECK(summary["mode_filter"]["feature_guides"].empty());
    CHECK(summary["method"]["whiten"]["reason"] == "no variance layer");

    auto unknown = run_modestack(denoise + "--renderer mantra -o " + dir.file("unknown/d.####.exr"));
    CHECK(unknown.exit_code == 2);
    CHECK_MESSAGE(unknown.err.find("--renderer 'mantra'") != std::string::npos, unknown.err);
    CHECK_MESSAGE(unknown.err.find("arnold, renderman, karma") != std::string::npos, unknown.err);
}

TEST_CASE(
    "renderer conventions: --conventions FILE replaces the table, a bad one is one line naming the file")
{
    TempDir dir;
    render_own_shot(dir);
    // A studio's own names, in a table of its own.
    const std::string input =
        rename_shot(dir, "studio", {{"DiffInd", "gi"}, {"DiffCol", "refl_colour"}, {"Normal", "nrm"}},
                    {{"studio/pipeline", "v3"}});
    const std::string table = dir.file("studio.json");
    std::ofstream(table) << R"({"format": "modestack renderer conventions 1", "renderers": [
        {"name": "studio", "detect": {"attributes": ["studio/*"]}, "light_layers": [{"layer": "gi", "colour": "refl_colour"}],
         "guides": {"albedo": ["refl_colour"], "normal": ["nrm"]}, "variance": ["{layer}_var"],
         "beauty": {"layer": "", "sum": ["gi"]}}]})";
    auto studio = run_modestack("denoise " + input + " --layer gi -q --conventions " + table +
                                " --mode-filter-guides albedo,normal --json " + dir.file("studio_run.json") +
                                " -o " + dir.file("studio_den/d.####.exr"));
    REQUIRE_MESSAGE(studio.exit_code == 0, studio.err);
    const nlohmann::json renderer = load_json(dir.file("studio_run.json"))["renderer"];
    CHECK(renderer["name"] == "studio");
    CHECK(renderer["detected_by"] == "header attribute studio/pipeline");
    CHECK(renderer["conventions"] == table);
    CHECK(renderer["guides"]["normal"]["found"] == "nrm");

    const std::pair<std::string, std::string> bad_tables[] = {
        {"{\"format\": \"modestack renderer conventions 1\", \"renderers\": [", "not valid JSON"},
        {R"({"format": "modestack renderer conventions 1", "renderers": [{"name": "x", "guides": {"shadow": ["S"]}}]})",
         "renderers[0].guides.shadow is not one of albedo, normal, depth"},
        {R"({"format": "modestack renderer conventions 1", "renderers": [{"name": "x", "variance": ["{aov}_var"]}]})",
         "renderers[0].variance[0] '{aov}_var' has a placeholder other than {layer}"},
        {R"({"format": "modestack renderer conventions 1", "renderers": [{"name": "x",
            "light_layers": [{"layer": "a"}], "beauty": {"layer": "", "sum": ["a", "b"]}}]})",
         "'b', which is not one of its light_layers"},
        {R"({"format": "modestack renderer conventions 1", "renderers": [{"name": "x",
            "light_layers": [{"layer": "a", "parts": ["a_direct"]}]}]})",
         "renderers[0].light_layers[0].parts names 'a_direct', which is not another of its light_layers"},
        {R"({"format": "other", "renderers": []})", "format must be"},
        {R"({"format": "modestack renderer conventions 1", "renderers": [{"name": "x", "guide": {}}]})",
         "renderers[0] has an unknown field \"guide\""},
    };
    int index = 0;
    for (const auto& [text, problem] : bad_tables) {
        const std::string bad = dir.file(fmt::format("bad{}.json", index++));
        std::ofstream(bad) << text;
        auto refused = run_modestack("denoise " + input + " --layer gi -q --conventions " + bad + " -o " +
                                     dir.file("bad/d.####.exr"));
        CAPTURE(text);
        CHECK(refused.exit_code == 1);
        CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
        CHECK_MESSAGE(refused.err.find(bad) != std::string::npos, refused.err);
        CHECK_MESSAGE(refused.err.find(problem) != std::string::npos, refused.err);
    }
    auto missing = run_modestack("denoise " + input + " --layer gi -q --conventions " +
                                 dir.file("none.json") + " -o " + dir.file("bad/d.####.exr"));
    CHECK(missing.exit_code == 1);
    CHECK(missing.err.find(dir.file("none.json")) != std::string::npos);
}

TEST_CASE(
    "renderer conventions: the compiled-in table is share/conventions.json and every renderer has all guides")
{
    CHECK(std::string(app::built_in_conventions_json()) ==
          testkit::read_text(std::string(MODESTACK_SOURCE_DIR) + "/share/conventions.json"));
    const app::ConventionTable table = app::parse_conventions(app::built_in_conventions_json(), "built-in");
    CHECK(table.names() == "modestack, cycles, arnold, renderman, karma, vray, redshift");
    for (const app::RendererConvention& renderer : table.renderers) {
        CAPTURE(renderer.name);
        for (const std::string& kind : app::guide_kinds())
            CHECK_FALSE(renderer.guides.at(kind).empty());
        CHECK_FALSE(renderer.light_layers.empty());
        CHECK_FALSE(renderer.beauty_sum.empty());
        CHECK_FALSE(renderer.detect_layers.empty());
    }
}

TEST_CASE("renderer conventions: detection by header attributes first, then by the most layers, else every "
          "renderer")
{
    const app::ConventionTable table = app::parse_conventions(app::built_in_conventions_json(), "built-in");
    auto header_of = [](std::vector<std::string> channels,
                        std::vector<std::pair<std::string, std::string>> attributes) {
        io::FrameHeader header;
        header.channel_names = channels;
        header.parts.push_back(header);
        header.attributes = std::move(attributes);
        return header;
    };
    // Cycles by its attributes, even with our renderer's layer names.
    auto cycles = app::choose_renderer(table, "auto",
                                       header_of({"ViewLayer.DiffCol.R", "ViewLayer.DiffIndVar.R"},
                                                 {{"cycles.ViewLayer.samples", "string \"4\""}}));
    CHECK(cycles.name == "cycles");
    CHECK(cycles.detected_by == "header attribute cycles.ViewLayer.samples");
    // A Software attribute's value.
    auto redshift = app::choose_renderer(
        table, "auto", header_of({"R", "G", "B"}, {{"Software", "string \"Redshift 3.5\""}}));
    CHECK(redshift.name == "redshift");
    // An attribute name is stronger evidence than a value: oiiotool writes its
    // whole command line into Software, here naming another renderer.
    auto rewritten = app::choose_renderer(
        table, "auto",
        header_of({"R", "G", "B"}, {{"Software", "string \"OpenImageIO 2.4 : oiiotool --attrib x Redshift\""},
                                    {"arnold/version", "string \"Arnold 7.2.1.0\""}}));
    CHECK(rewritten.name == "arnold");
    CHECK(rewritten.detected_by == "header attribute arnold/version");
    CHECK(
        app::choose_renderer(
            table, "auto", header_of({"R", "G", "B"}, {{"Software", "string \"OpenImageIO 2.4 Redshift\""}}))
            .name == "unknown");
    // Layers: V-Ray's render elements; Redshift's outnumber Arnold's N.
    CHECK(app::choose_renderer(table, "auto", header_of({"VRayDiffuseFilter.R", "VRayNormals.X"}, {})).name ==
          "vray");
    CHECK(app::choose_renderer(table, "auto", header_of({"DiffuseFilter.R", "GIRaw.R", "N.X"}, {})).name ==
          "redshift");
    // Nothing known: every renderer's names, ours first, each once.
    auto unknown = app::choose_renderer(table, "auto", header_of({"R", "G", "B", "beauty_noisy.R"}, {}));
    CHECK(unknown.name == "unknown");
    CHECK(unknown.conventions.size() == table.renderers.size());
    io::SelectedLayer beauty;
    beauty.name = "";
    const app::AuxiliaryCandidates candidates = app::auxiliary_candidates(unknown, {beauty});
    const auto& albedo = candidates[static_cast<size_t>(denoise::Auxiliary::Albedo)];
    REQUIRE(albedo.size() >= 3);
    CHECK(albedo[0] == std::vector<std::string>{"DiffCol"});
    CHECK(albedo[1] == std::vector<std::string>{"Denoising Albedo"});
    // The unnamed beauty's variance: Arnold's and RenderMan's names for it, not "_variance".
    CHECK(candidates[static_cast<size_t>(denoise::Auxiliary::Variance)] ==
          std::vector<std::vector<std::string>>{{"variance"}, {"mse"}});
    // Per denoised layer, after its own prefix.
    io::SelectedLayer diff_ind, gloss_ind;
    diff_ind.name = "ViewLayer.DiffInd";
    gloss_ind.name = "ViewLayer.GlossInd";
    const auto two = app::auxiliary_candidates(cycles, {diff_ind, gloss_ind});
    CHECK(two[static_cast<size_t>(denoise::Auxiliary::Variance)] ==
          std::vector<std::vector<std::string>>{{"ViewLayer.DiffIndVar", "ViewLayer.GlossIndVar"}});
    CHECK(two[static_cast<size_t>(denoise::Auxiliary::Normal)] ==
          std::vector<std::vector<std::string>>{{"ViewLayer.Normal"}, {"ViewLayer.Denoising Normal"}});
    CHECK_THROWS_AS(app::check_renderer_name(table, "mantra"), Error);
}
