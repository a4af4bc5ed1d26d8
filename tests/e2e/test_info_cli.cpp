// End-to-end: `modestack info` on real shots as a farm meets them: a frame cut
// short (named by the default check and by --check, exit 1, every bad frame
// listed), a chunk overwritten inside a file of the right size (found by --check
// only), an unpadded %d sequence (found by info and by denoise), and a two-part
// EXR whose parts' channels are all listed, in text and JSON.
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

std::string read_file(const std::string& path)
{
    std::ifstream file(path, std::ios::binary);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

std::vector<std::string> lines_of(const std::string& text)
{
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        lines.push_back(line);
    return lines;
}

// Overwrites `count` bytes in the middle of `path`; the size stays.
void overwrite_middle(const std::string& path, std::size_t count)
{
    std::string bytes = read_file(path);
    REQUIRE(bytes.size() > 4 * count);
    for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + count; ++i)
        bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Four frames of the built-in switch scene: multi-layer ZIP EXRs, 4 chunks each.
std::string render_shot(const TempDir& dir)
{
    auto render = run_modestack("render --scene switch --spp 1 --size 48x64 --frames 1-4 -q -o " +
                                dir.file("shot.####.exr"));
    REQUIRE_MESSAGE(render.exit_code == 0, render.err);
    return dir.file("shot.####.exr");
}

float noise(int frame, int x, int y, int c)
{
    unsigned hash = static_cast<unsigned>(frame * 7919 + x * 104729 + y * 1299709 + c * 15485863);
    hash ^= hash >> 13;
    hash *= 0x5bd1e995u;
    return static_cast<float>(hash % 1000) / 250.0f;
}

// A two-part EXR: "beauty" (R,G,B,A half, 40x36) and "aovs" (diffuse.R,G,B
// and depth.Z float, 32x24 at +4+6), ZIP scanlines, written with OIIO's
// multi-part API. (OIIO 2.4 cannot mix scanline and tiled parts.)
void write_two_parts(const std::string& path)
{
    OIIO::ImageSpec beauty(40, 36, 4, OIIO::TypeHalf);
    beauty.attribute("compression", "zip");
    beauty.attribute("name", "beauty");
    OIIO::ImageSpec aovs(32, 24, 4, OIIO::TypeFloat);
    aovs.x = 4;
    aovs.y = 6;
    // Every part of a file shares one display window.
    aovs.full_width = 40;
    aovs.full_height = 36;
    aovs.channelnames = {"diffuse.R", "diffuse.G", "diffuse.B", "depth.Z"};
    aovs.alpha_channel = -1;
    aovs.attribute("compression", "zip");
    aovs.attribute("name", "aovs");
    std::vector<OIIO::ImageSpec> specs{beauty, aovs};
    auto output = OIIO::ImageOutput::create(path);
    bool ok = output && output->open(path, 2, specs.data());
    for (int part = 0; ok && part < 2; ++part) {
        const OIIO::ImageSpec& spec = specs[part];
        std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * 4);
        for (std::size_t i = 0; i < pixels.size(); ++i)
            pixels[i] =
                0.25f + 0.001f * static_cast<float>((i + part) % 97); // ZIP packs it: no chunk is stored raw
        if (part > 0)
            ok = output->open(path, spec, OIIO::ImageOutput::AppendSubimage);
        ok = ok && output->write_image(OIIO::TypeFloat, pixels.data());
    }
    REQUIRE_MESSAGE((ok && output->close()),
                    "cannot write " << path << ": " << (output ? output->geterror() : ""));
}

} // namespace

TEST_CASE("info: a frame cut short is named by info and by info --check, with exit 1, after every frame")
{
    TempDir dir;
    const std::string shot = render_shot(dir);
    auto whole = run_modestack("info " + shot);
    REQUIRE_MESSAGE(whole.exit_code == 0, whole.err);
    CHECK(whole.err.empty());
    CHECK(whole.out.find("check        all 4 frames whole (chunk tables against file sizes)") !=
          std::string::npos);

    std::filesystem::resize_file(dir.file("shot.0003.exr"), 3000);
    for (const char* check : {"", " --check"}) {
        CAPTURE(check);
        auto cut = run_modestack("info " + shot + check + " --json " + dir.file("info.json"));
        CHECK(cut.exit_code == 1);
        REQUIRE(lines_of(cut.err).size() == 1);
        CHECK(cut.err.find("modestack: " + dir.file("shot.0003.exr") + ": truncated: ") == 0);
        CHECK(cut.err.find("past the end of the file (3000 bytes)") != std::string::npos);
        // The shot is still described, from its readable frames.
        CHECK(cut.out.find("check        1 of 4 frames bad: 3") != std::string::npos);
        CHECK(cut.out.find("DiffInd                      R,G,B half") != std::string::npos);
        auto json = nlohmann::json::parse(read_file(dir.file("info.json")));
        CHECK(json["check"] == (std::string(check).empty() ? "chunk_tables" : "every_chunk"));
        CHECK(json["bad_frames"] == std::vector<int>{3});
        REQUIRE(json["frame_checks"].size() == 4);
        CHECK(json["frame_checks"][1]["ok"] == true);
        CHECK(json["frame_checks"][1]["problem"].is_null());
        CHECK(json["frame_checks"][2]["frame"] == 3);
        CHECK(json["frame_checks"][2]["ok"] == false);
        CHECK(json["frame_checks"][2]["problem"].get<std::string>().rfind("truncated: ", 0) == 0);
    }

    // A farm wants the whole list: frame 1 empty, frame 4 cut inside its last chunk too.
    std::filesystem::resize_file(dir.file("shot.0001.exr"), 0);
    const auto size = std::filesystem::file_size(dir.file("shot.0004.exr"));
    std::filesystem::resize_file(dir.file("shot.0004.exr"), size - 10);
    auto several = run_modestack("info " + shot);
    CHECK(several.exit_code == 1);
    std::vector<std::string> lines = lines_of(several.err);
    REQUIRE(lines.size() == 3);
    CHECK(lines[0].find(dir.file("shot.0001.exr") + ": empty file (0 bytes)") != std::string::npos);
    CHECK(lines[1].find(dir.file("shot.0003.exr") + ": truncated: ") != std::string::npos);
    CHECK(lines[2].find(dir.file("shot.0004.exr") + ": truncated: the last chunk") != std::string::npos);
    CHECK(several.out.find("described    frame 2, the first whose header can be read") != std::string::npos);
}

TEST_CASE("info: a chunk overwritten inside a file of the right size is found by --check only")
{
    TempDir dir;
    const std::string shot = render_shot(dir);
    const auto size = std::filesystem::file_size(dir.file("shot.0002.exr"));
    overwrite_middle(dir.file("shot.0002.exr"), 64);
    REQUIRE(std::filesystem::file_size(dir.file("shot.0002.exr")) == size);

    auto cheap = run_modestack("info " + shot);
    CHECK_MESSAGE(cheap.exit_code == 0, cheap.err);
    CHECK(cheap.out.find("all 4 frames whole") != std::string::npos);

    auto checked = run_modestack("info " + shot + " --check --json " + dir.file("check.json"));
    CHECK(checked.exit_code == 1);
    REQUIRE(lines_of(checked.err).size() == 1);
    CHECK(checked.err.find("modestack: " + dir.file("shot.0002.exr") + ": cannot decode rows ") == 0);
    CHECK(checked.out.find("check        1 of 4 frames bad: 2 (every chunk decoded") != std::string::npos);
    auto json = nlohmann::json::parse(read_file(dir.file("check.json")));
    CHECK(json["bad_frames"] == std::vector<int>{2});
}

TEST_CASE("info and denoise find an unpadded %d sequence across 9 to 10, and %04d does not take it")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 12;
    layout.height = 8;
    testkit::write_sequence(dir.file("plain.%d.exr"), {7, 8, 9, 10, 11}, layout, noise);
    auto info = run_modestack("info '" + dir.file("plain.%d.exr") + "' --json " + dir.file("plain.json"));
    REQUIRE_MESSAGE(info.exit_code == 0, info.err);
    CHECK(info.out.find("frames       7-11 (5 frames, first 7, last 11)") != std::string::npos);
    auto json = nlohmann::json::parse(read_file(dir.file("plain.json")));
    CHECK(json["files"][3] == dir.file("plain.10.exr"));

    auto denoise =
        run_modestack("denoise '" + dir.file("plain.%d.exr") + "' -q -o '" + dir.file("out/d.%d.exr") + "'");
    REQUIRE_MESSAGE(denoise.exit_code == 0, denoise.err);
    for (const char* name : {"d.7.exr", "d.9.exr", "d.10.exr", "d.11.exr"})
        CHECK_MESSAGE(std::filesystem::exists(dir.file("out/") + name), name);

    auto padded = run_modestack("info '" + dir.file("plain.%04d.exr") + "'");
    CHECK(padded.exit_code == 1);
    CHECK(padded.err.find("no frames found on disk") != std::string::npos);
}

TEST_CASE(
    "info lists the channels of every part of a two-part EXR, in text and JSON, and --check decodes both")
{
    TempDir dir;
    write_two_parts(dir.file("parts.0001.exr"));
    write_two_parts(dir.file("parts.0002.exr"));
    auto info =
        run_modestack("info " + dir.file("parts.####.exr") + " --check --json " + dir.file("parts.json"));
    REQUIRE_MESSAGE(info.exit_code == 0, info.err);
    CHECK(info.out.find("format       openexr, 2 parts") != std::string::npos);
    CHECK(info.out.find("channels     8 in 2 parts") != std::string::npos);
    CHECK(info.out.find("  part 0 beauty: 4 channels, 40x36, scanline, compression zip") !=
          std::string::npos);
    CHECK(info.out.find("    (default)                  R,G,B,A half") != std::string::npos);
    CHECK(info.out.find("  part 1 aovs: 4 channels, 32x24+4+6, scanline, compression zip") !=
          std::string::npos);
    CHECK(info.out.find("    depth                      Z float") != std::string::npos);
    CHECK(info.out.find("    diffuse                    R,G,B float") != std::string::npos);
    auto json = nlohmann::json::parse(read_file(dir.file("parts.json")));
    CHECK(json["parts"] == 2);
    REQUIRE(json["part_list"].size() == 2);
    CHECK(json["part_list"][1]["name"] == "aovs");
    CHECK(json["part_list"][1]["data_window"]["y"] == 6);
    std::set<std::string> channels;
    for (const auto& part : json["part_list"])
        for (const auto& layer : part["layers"])
            for (const auto& channel : layer["channels"])
                channels.insert(channel["name"].get<std::string>());
    CHECK(channels ==
          std::set<std::string>{"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B", "depth.Z"});

    // The file ends with part 1's last chunk, and its ZIP stream with the checksum.
    std::string bytes = read_file(dir.file("parts.0002.exr"));
    for (std::size_t i = bytes.size() - 8; i < bytes.size(); ++i)
        bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
    std::ofstream(dir.file("parts.0002.exr"), std::ios::binary | std::ios::trunc) << bytes;
    CHECK(run_modestack("info " + dir.file("parts.####.exr")).exit_code == 0);
    auto checked = run_modestack("info " + dir.file("parts.####.exr") + " --check");
    CHECK(checked.exit_code == 1);
    CHECK(checked.err.find(dir.file("parts.0002.exr") + ": cannot decode part 1, rows ") !=
          std::string::npos);
}
