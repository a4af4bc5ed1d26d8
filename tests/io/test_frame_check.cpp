// io/frame_check.h: a whole file passes both checks, and a file cut anywhere
// past its magic number fails the chunk table check, whatever its layout
// (ZIP scanlines, one-line ZIPS chunks, tiles with MIP levels, two parts);
// damage inside a chunk passes that check and fails the decode.
#include "io/frame_check.h"
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace modestack;
using modestack::testkit::TempDir;

namespace {

std::string read_bytes(const std::string& path)
{
    std::ifstream file(path, std::ios::binary);
    std::stringstream bytes;
    bytes << file.rdbuf();
    return bytes.str();
}

void write_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

float smooth(int frame, int x, int y, int c)
{
    return 0.25f + 0.01f * x + 0.02f * y + 0.1f * c + frame;
}

// A tiled file with MIP levels, or two scanline parts, written with OIIO.
void write_special(const std::string& path, bool mip_levels)
{
    OIIO::ImageSpec spec(24, 20, 3, OIIO::TypeHalf);
    spec.attribute("compression", "zip");
    std::vector<OIIO::ImageSpec> specs{spec, spec};
    specs[0].attribute("name", "a");
    specs[1].attribute("name", "b");
    if (mip_levels) {
        spec.tile_width = spec.tile_height = 8;
        spec.attribute("textureformat", "Plain Texture"); // OIIO then writes MIP-map levels
    }
    auto output = OIIO::ImageOutput::create(path);
    bool ok = output && (mip_levels ? output->open(path, spec) : output->open(path, 2, specs.data()));
    const int levels = mip_levels ? 5 : 2; // 24x20, 12x10, 6x5, 3x2, 1x1
    for (int level = 0, width = 24, height = 20; ok && level < levels; ++level) {
        std::vector<float> pixels(static_cast<std::size_t>(width) * height * 3);
        for (std::size_t i = 0; i < pixels.size(); ++i)
            pixels[i] = smooth(level, static_cast<int>(i / 3) % width, static_cast<int>(i / 3) / width,
                               static_cast<int>(i % 3));
        if (level > 0) {
            OIIO::ImageSpec next = mip_levels ? spec : specs[level];
            if (mip_levels) {
                next.width = next.full_width = width;
                next.height = next.full_height = height;
            }
            ok = output->open(path, next,
                              mip_levels ? OIIO::ImageOutput::AppendMIPLevel
                                         : OIIO::ImageOutput::AppendSubimage);
        }
        ok = ok && output->write_image(OIIO::TypeFloat, pixels.data());
        if (mip_levels) {
            width = std::max(1, width / 2);
            height = std::max(1, height / 2);
        }
    }
    REQUIRE_MESSAGE((ok && output->close()), path << ": " << (output ? output->geterror() : ""));
}

} // namespace

TEST_CASE("frame check: whole files pass, and a cut anywhere fails the chunk table check, in every layout")
{
    TempDir dir;
    testkit::ExrLayout zip;
    zip.width = 20;
    zip.height = 40; // 3 chunks of 16 lines
    testkit::write_exr(dir.file("zip.exr"), zip, 1, smooth);
    testkit::ExrLayout zips = zip;
    zips.compression = "zips"; // 40 chunks of 1 line
    testkit::write_exr(dir.file("zips.exr"), zips, 1, smooth);
    write_special(dir.file("mip.exr"), true);
    write_special(dir.file("parts.exr"), false);
    for (const char* name : {"zip.exr", "zips.exr", "mip.exr", "parts.exr"}) {
        CAPTURE(name);
        const std::string whole = read_bytes(dir.file(name));
        CHECK(io::check_chunk_tables(dir.file(name)).empty());
        CHECK(io::check_every_chunk(dir.file(name)).empty());
        int missed = 0;
        // Every byte through the headers and tables and at the end; every 4th in the chunks between.
        for (std::size_t size = 8; size < whole.size();
             size += size < 512 || size + 32 > whole.size() ? 1 : 4) {
            write_bytes(dir.file("cut.exr"), whole.substr(0, size));
            if (io::check_chunk_tables(dir.file("cut.exr")).empty()) {
                ++missed;
                MESSAGE("not found: cut at " << size << " of " << whole.size());
            }
        }
        CHECK(missed == 0);
    }
}

TEST_CASE("frame check: a damaged chunk passes the table check and fails the decode, naming the part")
{
    TempDir dir;
    write_special(dir.file("parts.exr"), false);
    std::string bytes = read_bytes(dir.file("parts.exr"));
    // The file ends with part 1's last chunk, and its ZIP stream with the checksum.
    for (std::size_t i = bytes.size() - 6; i < bytes.size(); ++i)
        bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
    write_bytes(dir.file("parts.exr"), bytes);
    CHECK(io::check_chunk_tables(dir.file("parts.exr")).empty());
    const std::string problem = io::check_every_chunk(dir.file("parts.exr"));
    CHECK_MESSAGE(problem.rfind("cannot decode part 1, rows ", 0) == 0, problem);
}
