// End-to-end: multi-part EXR in and out. A shot rendered by our renderer is
// re-parted here with OIIO's C++ API (the way Arnold, Karma or Nuke write AOVs:
// a part per layer, its channels bare R, G, B) and denoised by the real binary:
// the same denoised pixels and sigma as the single-part shot, the input's parts,
// names, pixel types and per-part attributes kept, pass-through parts
// bit-exact, --single-part flattening, tiled parts, compare, and a bad
// multi-part file refused with one line.
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kFrames = 6;

std::string frame_file(const std::string& printf_pattern, int frame)
{
    char name[4096];
    std::snprintf(name, sizeof name, printf_pattern.c_str(), frame);
    return name;
}

// One part of a re-parted file: its name and, per channel, (name in the part, name in the single-part file).
struct PartPlan {
    std::string name;
    std::vector<std::pair<std::string, std::string>> channels;
};

// Every part of a file as read back: name, spec and pixels in native types.
struct ReadPart {
    std::string name;
    OIIO::ImageSpec spec;
    std::vector<unsigned char> native;
};

std::vector<ReadPart> read_parts(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    REQUIRE_MESSAGE(input, OIIO::geterror());
    std::vector<ReadPart> parts;
    for (int subimage = 0; input->seek_subimage(subimage, 0); ++subimage) {
        ReadPart part;
        part.spec = input->spec();
        part.name = part.spec.get_string_attribute("oiio:subimagename");
        part.native.resize(part.spec.image_bytes(true));
        REQUIRE(
            input->read_image(subimage, 0, 0, part.spec.nchannels, OIIO::TypeUnknown, part.native.data()));
        parts.push_back(std::move(part));
    }
    return parts;
}

// The bytes of channel `channel` of `part`, pixel after pixel.
std::vector<unsigned char> channel_bytes(const ReadPart& part, const std::string& channel)
{
    const int index = part.spec.channelindex(channel);
    REQUIRE_MESSAGE(index >= 0, channel);
    std::size_t offset = 0, pixel_bytes = part.spec.pixel_bytes(true);
    for (int c = 0; c < index; ++c)
        offset += part.spec.channelformat(c).size();
    const std::size_t size = part.spec.channelformat(index).size();
    const std::size_t pixels = static_cast<std::size_t>(part.spec.width) * part.spec.height;
    std::vector<unsigned char> bytes(pixels * size);
    for (std::size_t p = 0; p < pixels; ++p)
        std::memcpy(bytes.data() + p * size, part.native.data() + p * pixel_bytes + offset, size);
    return bytes;
}

// Writes `source` (a single-part file) as the parts of `plan`, each channel in its own
// pixel type, with a per-part attribute "studio:part" naming the part; tiled when `tile` > 0.
void write_reparted(const std::string& source, const std::string& path, const std::vector<PartPlan>& plan,
                    int tile)
{
    const std::vector<ReadPart> whole = read_parts(source);
    REQUIRE(whole.size() == 1);
    std::vector<OIIO::ImageSpec> specs;
    std::vector<std::vector<unsigned char>> pixels;
    for (const PartPlan& part : plan) {
        OIIO::ImageSpec spec(whole[0].spec.width, whole[0].spec.height,
                             static_cast<int>(part.channels.size()), OIIO::TypeHalf);
        spec.channelnames.clear();
        spec.channelformats.clear();
        std::vector<std::vector<unsigned char>> columns;
        for (const auto& [name, source_name] : part.channels) {
            spec.channelnames.push_back(name);
            spec.channelformats.push_back(
                whole[0].spec.channelformat(whole[0].spec.channelindex(source_name)));
            columns.push_back(channel_bytes(whole[0], source_name));
        }
        spec.alpha_channel = spec.channelindex("A");
        spec.attribute("compression", "zip");
        spec.attribute("oiio:subimagename", part.name);
        spec.attribute("studio:part", part.name);
        if (tile > 0) {
            spec.tile_width = spec.tile_height = tile;
            spec.tile_depth = 1;
        }
        const std::size_t count = static_cast<std::size_t>(spec.width) * spec.height;
        std::vector<unsigned char> packed;
        for (std::size_t p = 0; p < count; ++p)
            for (std::size_t c = 0; c < columns.size(); ++c) {
                const std::size_t size = spec.channelformats[c].size();
                packed.insert(packed.end(), columns[c].begin() + p * size,
                              columns[c].begin() + (p + 1) * size);
            }
        specs.push_back(spec);
        pixels.push_back(std::move(packed));
    }
    auto output = OIIO::ImageOutput::create(path);
    bool ok = output && output->open(path, static_cast<int>(specs.size()), specs.data());
    for (std::size_t part = 0; ok && part < specs.size(); ++part) {
        if (part > 0)
            ok = output->open(path, specs[part], OIIO::ImageOutput::AppendSubimage);
        ok = ok && output->write_image(OIIO::TypeUnknown, pixels[part].data());
    }
    REQUIRE_MESSAGE((ok && output->close()), (output ? output->geterror() : OIIO::geterror()));
}

// The Arnold/Karma-like parts of our renderer's frame: the beauty as part "rgba", DiffInd
// as part "DiffInd" (both bare R, G, B), every other layer in part "aux" under its own name.
std::vector<PartPlan> aov_parts(const std::string& source)
{
    std::vector<PartPlan> plan{{"rgba", {}}, {"DiffInd", {}}, {"aux", {}}};
    for (const std::string& name : testkit::read_channel_names(source)) {
        const std::size_t dot = name.rfind('.');
        const std::string layer = name.substr(0, dot), component = name.substr(dot + 1);
        if (layer == "Combined")
            plan[0].channels.push_back({component, name});
        else if (layer == "DiffInd")
            plan[1].channels.push_back({component, name});
        else
            plan[2].channels.push_back({name, name});
    }
    return plan;
}

// The shot both tests use: our renderer's frames, and the same frames re-parted.
struct Shots {
    TempDir dir;
    std::string single, parted, tiled;
};

void make_shots(Shots& shots)
{
    shots.single = shots.dir.file("single.%04d.exr");
    shots.parted = shots.dir.file("parted.%04d.exr");
    shots.tiled = shots.dir.file("tiled.%04d.exr");
    auto render = run_modestack("render --scene orbit --frames 1-" + std::to_string(kFrames) +
                                " --spp 2 --size 48x36 -q -o " + shots.dir.file("single.####.exr"));
    REQUIRE_MESSAGE(render.exit_code == 0, render.err);
    for (int frame = 1; frame <= kFrames; ++frame) {
        const std::string source = frame_file(shots.single, frame);
        write_reparted(source, frame_file(shots.parted, frame), aov_parts(source), 0);
        write_reparted(source, frame_file(shots.tiled, frame), aov_parts(source), 16);
    }
}

std::string sequence_of(const std::string& printf_pattern)
{
    std::string pattern = printf_pattern;
    pattern.replace(pattern.find("%04d"), 4, "####");
    return pattern;
}

} // namespace

TEST_CASE(
    "denoise of a multi-part shot: the single-part shot's pixels, in the input's parts, names and types")
{
    Shots shots;
    make_shots(shots);
    const std::string denoised_single = shots.dir.file("out/single.%04d.exr");
    const std::string denoised_parted = shots.dir.file("out/parted.%04d.exr");
    for (const auto& [input, output] :
         {std::pair{shots.single, denoised_single}, {shots.parted, denoised_parted}}) {
        auto result =
            run_modestack("denoise " + sequence_of(input) + " --layer DiffInd -q -o " + sequence_of(output));
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::vector<ReadPart> input = read_parts(frame_file(shots.parted, frame));
        const std::vector<ReadPart> output = read_parts(frame_file(denoised_parted, frame));
        const std::vector<ReadPart> single = read_parts(frame_file(denoised_single, frame));
        REQUIRE(output.size() == 3);
        CHECK(output[0].name == "rgba");
        CHECK(output[1].name == "DiffInd");
        CHECK(output[2].name == "aux");
        for (std::size_t p = 0; p < output.size(); ++p) {
            CHECK(output[p].spec.get_string_attribute("studio:part") == output[p].name);
            CHECK(output[p].spec.tile_width == 0);
            CHECK(output[p].spec.get_string_attribute("compression") == "zip");
        }
        // The untouched parts, bit for bit; DiffInd's part gains its sigma, every channel in its own type.
        CHECK(output[0].native == input[0].native);
        CHECK(output[2].native == input[2].native);
        CHECK(output[0].spec.channelnames == input[0].spec.channelnames);
        CHECK(output[2].spec.channelnames == input[2].spec.channelnames);
        const ReadPart& diffuse = output[1];
        CHECK(std::set<std::string>(diffuse.spec.channelnames.begin(), diffuse.spec.channelnames.end()) ==
              std::set<std::string>{"R", "G", "B", "sigma.R", "sigma.G", "sigma.B"});
        for (const char* component : {"R", "G", "B"}) {
            CHECK(diffuse.spec.channelformat(diffuse.spec.channelindex(component)) ==
                  input[1].spec.channelformat(input[1].spec.channelindex(component)));
            // The same denoised values and sigma as the single-part shot's.
            CHECK(channel_bytes(diffuse, component) ==
                  channel_bytes(single[0], std::string("DiffInd.") + component));
            CHECK(channel_bytes(diffuse, std::string("sigma.") + component) ==
                  channel_bytes(single[0], std::string("DiffInd.sigma.") + component));
            CHECK(channel_bytes(diffuse, component) !=
                  channel_bytes(input[1], component)); // denoised, not copied
        }
    }
    // Read back, the parted output's layers are the single-part output's: compare finds them equal.
    auto compare =
        run_modestack("compare " + sequence_of(denoised_parted) + " " + sequence_of(denoised_single) +
                      " --layer DiffInd.sigma --json " + shots.dir.file("compare.json") + " -q");
    CHECK_MESSAGE(compare.exit_code == 0, compare.err);
    const nlohmann::json summary = nlohmann::json::parse(testkit::read_text(shots.dir.file("compare.json")));
    REQUIRE(summary["per_frame"].size() == kFrames);
    for (const auto& frame : summary["per_frame"])
        CHECK(frame["relative_mse"].get<double>() == 0.0);
}

TEST_CASE(
    "denoise of a multi-part shot: --single-part flattens, tiled parts read alike, bad files give one line")
{
    Shots shots;
    make_shots(shots);
    const std::string denoised_single = shots.dir.file("out/single.%04d.exr");
    const std::string flattened = shots.dir.file("out/flat.%04d.exr");
    const std::string from_tiles = shots.dir.file("out/tiled.%04d.exr");
    for (const auto& [input, output, options] : {std::tuple{shots.single, denoised_single, ""},
                                                 {shots.parted, flattened, " --single-part"},
                                                 {shots.tiled, from_tiles, ""}}) {
        // The beauty as copied: the parted shot's beauty part 'rgba' is not our renderer's
        // 'Combined', so --update-beauty (the default where the beauty is known) would differ.
        auto result =
            run_modestack("denoise " + sequence_of(input) + " --layer DiffInd --no-update-beauty -q" +
                          options + " -o " + sequence_of(output));
        REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    }
    for (int frame = 1; frame <= kFrames; ++frame) {
        CAPTURE(frame);
        const std::vector<ReadPart> single = read_parts(frame_file(denoised_single, frame));
        const std::vector<ReadPart> flat = read_parts(frame_file(flattened, frame));
        REQUIRE(flat.size() == 1);
        std::set<std::string> names(flat[0].spec.channelnames.begin(), flat[0].spec.channelnames.end());
        for (const char* name :
             {"rgba.R", "rgba.A", "DiffInd.R", "DiffInd.sigma.B", "Normal.X", "DiffIndVar.G"})
            CHECK_MESSAGE(names.count(name) == 1, name);
        CHECK(names.count("R") == 0);
        for (const char* name : {"DiffInd.R", "DiffInd.G", "DiffInd.B", "DiffInd.sigma.R", "Normal.X"})
            CHECK(channel_bytes(flat[0], name) == channel_bytes(single[0], name));
        CHECK(channel_bytes(flat[0], "rgba.G") == channel_bytes(single[0], "Combined.G"));

        const std::vector<ReadPart> tiled = read_parts(frame_file(from_tiles, frame));
        REQUIRE(tiled.size() == 3);
        CHECK(tiled[1].spec.tile_width == 0); // written as scanlines, as a tiled single-part input is
        for (const char* component : {"R", "G", "B"})
            CHECK(channel_bytes(tiled[1], component) ==
                  channel_bytes(single[0], std::string("DiffInd.") + component));
        CHECK(tiled[2].native == read_parts(frame_file(shots.tiled, frame))[2].native);
    }

    // Frame 3 with parts of different data windows; frame 4 cut short.
    const std::string bad = shots.dir.file("bad.%04d.exr");
    for (int frame = 1; frame <= kFrames; ++frame)
        std::filesystem::copy_file(frame_file(shots.parted, frame), frame_file(bad, frame));
    {
        OIIO::ImageSpec first(48, 36, 3, OIIO::TypeHalf), second(40, 36, 3, OIIO::TypeHalf);
        second.full_width = 48; // one display window, as a valid multi-part file has
        first.attribute("oiio:subimagename", "DiffInd");
        second.attribute("oiio:subimagename", "DiffDir");
        std::vector<OIIO::ImageSpec> specs{first, second};
        std::vector<float> zeros(48 * 36 * 3, 0.5f);
        const std::string path = frame_file(bad, 3);
        std::filesystem::remove(path);
        auto output = OIIO::ImageOutput::create(path);
        REQUIRE_MESSAGE((output && output->open(path, 2, specs.data())), (output ? output->geterror() : ""));
        REQUIRE(output->write_image(OIIO::TypeFloat, zeros.data()));
        REQUIRE(output->open(path, second, OIIO::ImageOutput::AppendSubimage));
        REQUIRE(output->write_image(OIIO::TypeFloat, zeros.data()));
        REQUIRE(output->close());
    }
    auto windows = run_modestack("denoise " + sequence_of(bad) + " --layer DiffInd -q -o " +
                                 shots.dir.file("bad_out/d.####.exr"));
    CHECK(windows.exit_code == 1);
    CHECK(std::count(windows.err.begin(), windows.err.end(), '\n') == 1);
    CHECK_MESSAGE(windows.err.find("bad.0003.exr: part 1 'DiffDir' has data window 40x36") !=
                      std::string::npos,
                  windows.err);
    std::filesystem::remove(frame_file(bad, 3));
    std::filesystem::resize_file(frame_file(bad, 4), std::filesystem::file_size(frame_file(bad, 4)) - 200);
    auto cut = run_modestack("denoise " + sequence_of(bad) + " --frames 4-6 --layer DiffInd -q -o " +
                             shots.dir.file("bad_out/d.####.exr"));
    CHECK(cut.exit_code == 1);
    CHECK(std::count(cut.err.begin(), cut.err.end(), '\n') == 1);
    CHECK_MESSAGE(cut.err.find("bad.0004.exr: ") != std::string::npos, cut.err);
    CHECK(!std::filesystem::exists(shots.dir.file("bad_out/d.0004.exr")));
}
