// ZIP and ZIPS inputs are decoded with libdeflate (io/detail/zip_scanline_reader.h):
// every read must return exactly what OpenImageIO's reader returns, for any rows,
// channels, pixel types and data window, and a corrupt chunk must be an error
// naming the file.
#include "core/common/error.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <OpenImageIO/imageio.h>
#include <openexr.h>

#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

using namespace modestack;
using testkit::TempDir;

namespace {

// A reader through libdeflate, or (with `through_openimageio`) through OpenImageIO.
std::unique_ptr<io::SequenceReader> open_reader(const std::string& pattern, const std::vector<std::string>& layers,
                                                bool through_openimageio)
{
    return std::make_unique<io::SequenceReader>(io::find_input_sequence(pattern), layers,
                                                through_openimageio ? io::ExrCodec::OpenImageIO
                                                                    : io::ExrCodec::Libdeflate);
}

// Every band of `band_rows` rows from `first_row`, native and selected, both ways.
void check_same_reads(const std::string& pattern, const std::vector<std::string>& layers, int first_row, int band_rows)
{
    auto ours = open_reader(pattern, layers, false);
    auto theirs = open_reader(pattern, layers, true);
    const int height = ours->height(), width = ours->width(), channels = ours->selected_channel_count();
    for (int frame = 0; frame < ours->frame_count(); ++frame)
        for (int row = first_row; row < height; row += band_rows) {
            const int end = std::min(height, row + band_rows);
            std::vector<unsigned char> native_ours, native_theirs;
            ours->read_native(frame, row, end, native_ours);
            theirs->read_native(frame, row, end, native_theirs);
            CHECK(native_ours == native_theirs);
            std::vector<float> selected_ours(static_cast<size_t>(width) * (end - row) * channels),
                selected_theirs(selected_ours.size());
            ours->read_selected(frame, row, end, selected_ours.data());
            theirs->read_selected(frame, row, end, selected_theirs.data());
            CHECK(std::memcmp(selected_ours.data(), selected_theirs.data(), selected_ours.size() * sizeof(float)) ==
                  0);
        }
}

float pattern_value(int frame, int x, int y, int c)
{
    return c == 8 ? static_cast<float>((x * 7 + y + frame) % 50) : std::cos(0.3f * x - 0.7f * y + c + frame) * 4;
}

}  // namespace

TEST_CASE("ZIP reader: the same rows as OpenImageIO's, for ZIP and ZIPS, any band, mixed types, scattered layers")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 37;
    layout.height = 45;  // two full 16-row chunks and a short one
    // Not an RGB layer besides the default one, so that {} selects R, G, B (A).
    layout.channel_names = {"R", "G", "B", "A", "position.X", "position.Y", "position.Z", "Z", "id"};
    layout.channel_types = {"half", "half", "half", "half", "float", "float", "float", "float", "uint"};
    for (const std::string compression : {"zip", "zips"}) {
        CAPTURE(compression);
        layout.compression = compression;
        testkit::write_sequence(dir.file(compression + ".%04d.exr"), {1, 2, 3}, layout, pattern_value);
        for (const std::vector<std::string>& layers : std::vector<std::vector<std::string>>{{}, {"position"}}) {
            for (int band_rows : {1, 5, 16, 45}) {
                CAPTURE(band_rows);
                check_same_reads(dir.file(compression + ".####.exr"), layers, 0, band_rows);
                check_same_reads(dir.file(compression + ".####.exr"), layers, 3, band_rows);
            }
        }
    }
}

TEST_CASE("ZIP reader: a data window off the origin reads as OpenImageIO reads it")
{
    TempDir dir;
    for (int frame = 1; frame <= 3; ++frame) {
        OIIO::ImageSpec spec(21, 19, 3, OIIO::TypeHalf);
        spec.x = 3;
        spec.y = -5;
        spec.full_width = 40;
        spec.full_height = 40;
        spec.attribute("compression", "zip");
        std::vector<float> pixels(21 * 19 * 3);
        for (size_t i = 0; i < pixels.size(); ++i)
            pixels[i] = std::sin(0.37f * static_cast<float>(i) + frame);
        const std::string path = dir.file(fmt::format("offset.{:04d}.exr", frame));
        auto output = OIIO::ImageOutput::create(path);
        REQUIRE(output);
        REQUIRE(output->open(path, spec));
        REQUIRE(output->write_image(OIIO::TypeFloat, pixels.data()));
        REQUIRE(output->close());
    }
    check_same_reads(dir.file("offset.####.exr"), {}, 0, 7);
}

TEST_CASE("ZIP reader: a corrupt chunk is an error naming the file, not wrong pixels")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 64;
    layout.height = 32;
    testkit::write_sequence(dir.file("bad.%04d.exr"), {1, 2, 3}, layout, pattern_value);
    // Overwrite the middle of frame 2's second chunk with bytes no DEFLATE stream ends on.
    const std::string path = dir.file("bad.0002.exr");
    exr_context_t context = nullptr;
    exr_context_initializer_t initializer = EXR_DEFAULT_CONTEXT_INITIALIZER;
    REQUIRE(exr_start_read(&context, path.c_str(), &initializer) == EXR_ERR_SUCCESS);
    exr_chunk_info_t chunk;
    REQUIRE(exr_read_scanline_chunk_info(context, 0, 16, &chunk) == EXR_ERR_SUCCESS);
    exr_finish(&context);
    REQUIRE(chunk.packed_size < chunk.unpacked_size);
    {
        std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
        file.seekp(static_cast<std::streamoff>(chunk.data_offset + chunk.packed_size / 2));
        const std::string garbage(8, '\xff');
        file.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
    }
    auto reader = open_reader(dir.file("bad.####.exr"), {}, false);
    std::vector<unsigned char> native;
    reader->read_native(1, 0, 16, native);  // the first chunk is intact
    try {
        reader->read_native(1, 16, 32, native);
        FAIL("a corrupt chunk was read");
    } catch (const Error& error) {
        CHECK(std::string(error.what()).find("bad.0002.exr") != std::string::npos);
        CHECK(std::string(error.what()).find("cannot read rows 16-31 (corrupt chunk at row 16") != std::string::npos);
    }
}
