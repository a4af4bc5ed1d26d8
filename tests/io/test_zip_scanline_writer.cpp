// ZIP and ZIPS outputs are written with libdeflate (io/detail/zip_scanline_writer.h):
// the files must hold exactly what OpenImageIO's writer would write (every
// channel's bits, the header), whatever the channel types, data window or height,
// the output format (only the written channels, float, ZIPS from ZIP), and stay
// readable by OpenEXR where a chunk does not compress; any other compression
// asked for is OpenImageIO's to write.
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <OpenImageIO/imageio.h>
#include <openexr.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <iterator>

using namespace modestack;
using testkit::TempDir;

namespace {

// A frame whose data window starts at (3, -5) inside a larger display window.
void write_offset_frame(const std::string& path, int width, int height, const std::string& compression)
{
    OIIO::ImageSpec spec(width, height, 4, OIIO::TypeHalf);
    spec.channelnames = {"R", "G", "B", "depth.Z"};
    spec.channelformats = {OIIO::TypeHalf, OIIO::TypeHalf, OIIO::TypeHalf, OIIO::TypeFloat};
    spec.alpha_channel = -1;
    spec.x = 3;
    spec.y = -5;
    spec.full_x = 0;
    spec.full_y = -8;
    spec.full_width = width + 10;
    spec.full_height = height + 12;
    spec.attribute("compression", compression);
    spec.attribute("renderer", "offset test");
    std::vector<float> pixels(static_cast<size_t>(width) * height * 4);
    for (size_t i = 0; i < pixels.size(); ++i)
        pixels[i] = std::sin(0.37f * static_cast<float>(i)) * 3;
    auto output = OIIO::ImageOutput::create(path);
    REQUIRE(output);
    REQUIRE(output->open(path, spec));
    REQUIRE(output->write_image(OIIO::TypeFloat, pixels.data()));
    REQUIRE(output->close());
}

// Writes frame 0 of `reader` to `path` with the selected channels replaced and
// sigma channels appended, in bands of `band_rows`, through the ZIP writer or
// (with `through_openimageio`) through OpenImageIO, as `format` says.
void write_output(const std::string& path, io::SequenceReader& reader, int band_rows,
                  bool through_openimageio, const io::OutputFormat& format = {})
{
    const std::vector<std::string> extra{"sigma.R", "sigma.G", "sigma.B"};
    io::FrameOutput output(path, reader, 0, extra,
                           {io::HeaderAttribute::of_text("modestack:command", "modestack test"),
                            io::HeaderAttribute::of_integer("modestack:rank", 3),
                            io::HeaderAttribute::of_real("modestack:seconds", 1.5)},
                           through_openimageio ? io::ExrCodec::OpenImageIO : io::ExrCodec::Libdeflate,
                           io::PartLayout::AsInput, format);
    const int width = reader.width(), height = reader.height();
    const int selected = reader.selected_channel_count();
    std::vector<unsigned char> native;
    for (int row = 0; row < height; row += band_rows) {
        const int end = std::min(height, row + band_rows);
        const size_t pixels = static_cast<size_t>(width) * (end - row);
        reader.read_native(0, row, end, native);
        if (!output.needs_input_rows())
            native.clear();
        std::vector<float> replaced(pixels * selected), sigma(pixels * 3);
        for (size_t i = 0; i < replaced.size(); ++i)
            replaced[i] = 0.25f + 0.001f * static_cast<float>(i % 977) + static_cast<float>(row);
        for (size_t i = 0; i < sigma.size(); ++i)
            sigma[i] = 0.01f * static_cast<float>(i % 31);
        output.write_replaced_rows(row, end, native, replaced.data(), sigma.data());
    }
    output.commit();
}

std::string file_bytes(const std::string& path)
{
    std::ifstream file(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

// Every attribute OpenImageIO reports, as "name=value" lines.
std::string header_of(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    REQUIRE(input);
    const OIIO::ImageSpec& spec = input->spec();
    std::string text = fmt::format("{}x{}+{}+{} full {}x{}+{}+{}\n", spec.width, spec.height, spec.x, spec.y,
                                   spec.full_width, spec.full_height, spec.full_x, spec.full_y);
    for (int c = 0; c < spec.nchannels; ++c)
        text += spec.channelnames[c] + ":" + spec.channelformat(c).c_str() + "\n";
    for (const OIIO::ParamValue& attribute : spec.extra_attribs)
        text += attribute.name().string() + "=" + attribute.get_string() + "\n";
    return text;
}

// Both writers, the same content: same pixel bits and header, different
// compressed bytes (the ZIP writer really ran).
void check_same_as_openimageio(const std::string& input_pattern, const std::vector<std::string>& layers,
                               int band_rows, const io::OutputFormat& format = {})
{
    TempDir out;
    io::SequenceReader reader(io::find_input_sequence(input_pattern), layers);
    const std::string ours = out.file("ours.exr"), theirs = out.file("theirs.exr");
    write_output(ours, reader, band_rows, false, format);
    write_output(theirs, reader, band_rows, true, format);
    CHECK(testkit::read_native(ours) == testkit::read_native(theirs));
    CHECK(header_of(ours) == header_of(theirs));
    CHECK(file_bytes(ours) != file_bytes(theirs));
}

}  // namespace

TEST_CASE("ZIP writer: the same pixels and header as OpenImageIO's, for ZIP and ZIPS, any band height")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 37;
    layout.height = 45;  // two full 16-row chunks and a short one
    layout.channel_names = {"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B", "Z", "id"};
    layout.channel_types = {"half", "half", "half", "half", "half", "half", "half", "float", "uint"};
    // Names longer than 31 characters, as Cycles writes them, need OpenEXR's long-name flag.
    layout.channel_names.push_back("ViewLayer.Denoising Albedo.Y");
    layout.channel_types.push_back("half");
    layout.attributes = {{"renderer", "test"}, {"cycles.ViewLayer.synchronization_time", "00:00.00"}};
    for (const std::string compression : {"zip", "zips"}) {
        CAPTURE(compression);
        layout.compression = compression;
        testkit::write_sequence(dir.file(compression + ".%04d.exr"), {1, 2, 3}, layout,
                                [](int frame, int x, int y, int c) {
                                    return c == 8 ? static_cast<float>((x * 7 + y) % 50)
                                                  : std::cos(0.3f * x - 0.7f * y + c + frame) * 4;
                                });
        for (int band_rows : {1, 7, 16, 64}) {
            CAPTURE(band_rows);
            check_same_as_openimageio(dir.file(compression + ".####.exr"), {"diffuse"}, band_rows);
        }
    }
}

TEST_CASE("ZIP writer: a data window off the origin and float outputs are written as OpenImageIO writes them")
{
    TempDir dir;
    for (int frame = 1; frame <= 3; ++frame)
        write_offset_frame(dir.file(fmt::format("offset.{:04d}.exr", frame)), 21, 19, "zip");
    check_same_as_openimageio(dir.file("offset.####.exr"), {"depth"}, 16);
    check_same_as_openimageio(dir.file("offset.####.exr"), {}, 5);
}

TEST_CASE(
    "ZIP writer: only the written channels, float ones, ZIPS from ZIP are written as OpenImageIO writes "
    "them, and PIZ asked for goes through OpenImageIO")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 23;
    layout.height = 35;
    layout.channel_names = {"R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B", "Z"};
    layout.channel_types = {"half", "half", "half", "half", "half", "half", "half", "float"};
    testkit::write_sequence(dir.file("shot.%04d.exr"), {1, 2, 3}, layout, [](int frame, int x, int y, int c) {
        return std::cos(0.3f * x - 0.7f * y + c + frame) * 4;
    });
    const std::string shot = dir.file("shot.####.exr");
    io::OutputFormat only_float;
    only_float.only_written = true;
    only_float.written_type = io::WrittenType::Float;
    io::OutputFormat beauty_kept = only_float; // the bare R, G, B, A kept whole, as --update-beauty's beauty
    beauty_kept.kept_layers = {""};
    io::OutputFormat zips;
    zips.compression = "zips";
    for (const io::OutputFormat* format : {&only_float, &beauty_kept, &zips}) {
        check_same_as_openimageio(shot, {"diffuse"}, 9, *format);
        TempDir out;
        io::SequenceReader reader(io::find_input_sequence(shot), {"diffuse"});
        write_output(out.file("ours.exr"), reader, 9, false, *format);
        const std::vector<std::string> names = testkit::read_channel_names(out.file("ours.exr"));
        CHECK(names.size() == (format == &only_float ? 6u : format == &beauty_kept ? 10u : 11u));
        CHECK(testkit::read_string_attribute(out.file("ours.exr"), "compression") ==
              (format == &zips ? "zips" : "zip"));
    }
    io::OutputFormat piz;
    piz.compression = "piz";
    TempDir out;
    io::SequenceReader reader(io::find_input_sequence(shot), {"diffuse"});
    write_output(out.file("ours.exr"), reader, 9, false, piz);
    write_output(out.file("theirs.exr"), reader, 9, true, piz);
    CHECK(testkit::read_string_attribute(out.file("ours.exr"), "compression") == "piz");
    CHECK(file_bytes(out.file("ours.exr")) == file_bytes(out.file("theirs.exr")));
}

TEST_CASE("ZIP writer: a chunk that does not compress is stored as it is and reads back exactly")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 2;
    layout.height = 20;
    layout.compression = "zips";
    layout.channel_names = {"R", "G", "B", "noise.Y"};
    layout.channel_types = {"half", "half", "half", "float"};
    // 32-byte scanlines of random mantissas: DEFLATE's own framing outgrows what it saves.
    testkit::write_sequence(dir.file("raw.%04d.exr"), {1, 2, 3}, layout, [](int frame, int x, int y, int c) {
        std::uint32_t h = static_cast<std::uint32_t>((frame * 131 + y) * 977 + x) * 2654435761u + c;
        h ^= h >> 15, h *= 2246822519u, h ^= h >> 13;
        float value;
        h = (h & 0x807fffffu) | 0x3f000000u;  // random sign and mantissa, |value| in [0.5, 1)
        std::memcpy(&value, &h, sizeof value);
        return c == 3 ? value : 0.5f;
    });
    TempDir out;
    io::SequenceReader reader(io::find_input_sequence(dir.file("raw.####.exr")), {});
    write_output(out.file("ours.exr"), reader, 20, false);
    write_output(out.file("theirs.exr"), reader, 20, true);
    CHECK(testkit::read_native(out.file("ours.exr")) == testkit::read_native(out.file("theirs.exr")));

    // Some chunk is stored raw: its size on disk is its unpacked size.
    exr_context_t context = nullptr;
    exr_context_initializer_t initializer = EXR_DEFAULT_CONTEXT_INITIALIZER;
    REQUIRE(exr_start_read(&context, out.file("ours.exr").c_str(), &initializer) == EXR_ERR_SUCCESS);
    int chunks = 0, raw_chunks = 0;
    REQUIRE(exr_get_chunk_count(context, 0, &chunks) == EXR_ERR_SUCCESS);
    for (int chunk = 0; chunk < chunks; ++chunk) {
        exr_chunk_info_t info;
        REQUIRE(exr_read_scanline_chunk_info(context, 0, chunk, &info) == EXR_ERR_SUCCESS);
        raw_chunks += info.packed_size == info.unpacked_size;
    }
    exr_finish(&context);
    CHECK(chunks == 20);
    CHECK(raw_chunks >= 1);
}

TEST_CASE("ZIP writer: inputs it cannot copy exactly (tiled, PIZ) are written by OpenImageIO")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 20;
    layout.height = 18;
    layout.tile_size = 16;
    testkit::write_sequence(dir.file("tiled.%04d.exr"), {1, 2, 3}, layout,
                            [](int frame, int x, int y, int c) { return 0.1f * (x + y + c + frame); });
    layout.tile_size = 0;
    layout.compression = "piz";
    testkit::write_sequence(dir.file("piz.%04d.exr"), {1, 2, 3}, layout,
                            [](int frame, int x, int y, int c) { return 0.1f * (x + y + c + frame); });
    for (const std::string name : {"tiled", "piz"}) {
        CAPTURE(name);
        TempDir out;
        io::SequenceReader reader(io::find_input_sequence(dir.file(name + ".####.exr")), {});
        write_output(out.file("ours.exr"), reader, 7, false);
        write_output(out.file("theirs.exr"), reader, 7, true);
        CHECK(file_bytes(out.file("ours.exr")) == file_bytes(out.file("theirs.exr")));
    }
}
