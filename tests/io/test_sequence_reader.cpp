// Band reads of selected channels equal whole-frame reads, for scanline and tiled
// files; frames that disagree are refused before any work.
#include "core/common/error.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <fstream>

using namespace modestack;
using testkit::TempDir;

namespace {
const std::vector<std::string> kCyclesChannels{"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                                               "ViewLayer.Combined.A", "ViewLayer.Depth.Z",    "ViewLayer.DiffInd.R",
                                               "ViewLayer.DiffInd.G",  "ViewLayer.DiffInd.B"};
float pattern_value(int frame, int x, int y, int c) { return 0.25f * c + 0.01f * x + 0.1f * y + frame; }

testkit::ExrLayout cycles_layout(int width, int height, int tile)
{
    testkit::ExrLayout layout;
    layout.width = width;
    layout.height = height;
    layout.channel_names = kCyclesChannels;
    layout.channel_types = {"half", "half", "half", "half", "float", "half", "half", "half"};
    layout.tile_size = tile;
    return layout;
}
}  // namespace

TEST_CASE("band reads equal whole-frame reads (scanline and tiled, odd 257x89 size)")
{
    for (int tile : {0, 32}) {
        CAPTURE(tile);
        TempDir dir;
        testkit::write_sequence(dir.file("s.%04d.exr"), {1, 2, 3}, cycles_layout(257, 89, tile), pattern_value);
        io::SequenceReader reader(io::find_input_sequence(dir.file("s.####.exr")), {"DiffInd"});
        CHECK(reader.frame_count() == 3);
        CHECK(reader.selected_channel_count() == 3);
        std::vector<float> whole = testkit::read_channels(dir.file("s.0002.exr"), reader.selected_channel_names());
        std::vector<float> banded(whole.size());
        int rows_per_band = 17;  // deliberately not aligned to EXR blocks or tiles
        for (int row = 0; row < reader.height(); row += rows_per_band) {
            int end = std::min(reader.height(), row + rows_per_band);
            reader.read_selected(1, row, end, banded.data() + static_cast<size_t>(row) * reader.width() * 3);
        }
        CHECK(banded == whole);
    }
}

TEST_CASE("scattered channels (R and B of one layer, Z of another) are picked in the selection's order")
{
    TempDir dir;
    testkit::write_sequence(dir.file("s.%04d.exr"), {1, 2}, cycles_layout(8, 6, 0), pattern_value);
    io::SequenceReader reader(io::find_input_sequence(dir.file("s.####.exr")), {"DiffInd", "Combined"});
    CHECK(reader.selected_channel_count() == 6);
    std::vector<float> band(8 * 6 * 6);
    reader.read_selected(0, 0, 6, band.data());
    CHECK(band == testkit::read_channels(dir.file("s.0001.exr"), reader.selected_channel_names()));
}

TEST_CASE("selected channels converted from native rows equal a read of the selected channels")
{
    TempDir dir;
    testkit::write_sequence(dir.file("s.%04d.exr"), {1, 2}, cycles_layout(31, 9, 0), pattern_value);
    // Half (DiffInd, Combined) and float (Depth.Z) channels, scattered in the file; the
    // Combined layer's RGB, not its alpha.
    io::SequenceReader reader(io::find_input_sequence(dir.file("s.####.exr")), {"DiffInd", "Depth", "Combined"});
    CHECK(reader.selected_channel_count() == 7);
    CHECK(reader.has_unselected_channels(0));
    io::SequenceReader some(io::find_input_sequence(dir.file("s.####.exr")), {"DiffInd"});
    CHECK(some.has_unselected_channels(1));
    CHECK(some.native_pixel_bytes(1) == 7 * 2 + 4);
    for (const io::SequenceReader* selection : {&reader, &some}) {
        const size_t count = static_cast<size_t>(selection->selected_channel_count());
        std::vector<float> selected(31 * 5 * count), converted(selected.size(), -1.0f);
        selection->read_selected(1, 3, 8, selected.data());
        std::vector<unsigned char> native;
        selection->read_native(1, 3, 8, native);
        selection->selected_from_native(1, native.data(), 31 * 5, converted.data());
        CHECK(converted == selected);
    }
}

TEST_CASE("frames of a different size, a missing channel or a truncated file are refused up front")
{
    TempDir dir;
    testkit::write_sequence(dir.file("a.%04d.exr"), {1, 2}, cycles_layout(8, 6, 0), pattern_value);
    testkit::write_sequence(dir.file("a.%04d.exr"), {3}, cycles_layout(8, 5, 0), pattern_value);
    CHECK_THROWS_WITH_AS(io::SequenceReader(io::find_input_sequence(dir.file("a.####.exr")), {"DiffInd"}),
                         doctest::Contains("a.0003.exr: data window 8x5 differs"), Error);

    testkit::ExrLayout no_diffind = cycles_layout(8, 6, 0);
    no_diffind.channel_names = {"R", "G", "B"};
    no_diffind.channel_types = {};
    testkit::write_sequence(dir.file("b.%04d.exr"), {1}, cycles_layout(8, 6, 0), pattern_value);
    testkit::write_sequence(dir.file("b.%04d.exr"), {2}, no_diffind, pattern_value);
    CHECK_THROWS_WITH_AS(io::SequenceReader(io::find_input_sequence(dir.file("b.####.exr")), {"DiffInd"}),
                         doctest::Contains("b.0002.exr: channel 'ViewLayer.DiffInd.R' not found"), Error);

    testkit::write_sequence(dir.file("c.%04d.exr"), {1, 2}, cycles_layout(64, 64, 0), pattern_value);
    std::ifstream whole(dir.file("c.0002.exr"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(whole)), {});
    std::ofstream(dir.file("c.0002.exr"), std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
    io::SequenceReader reader(io::find_input_sequence(dir.file("c.####.exr")), {"DiffInd"});
    std::vector<float> band(64 * 64 * 3);
    CHECK_THROWS_WITH_AS(reader.read_selected(1, 0, 64, band.data()), doctest::Contains("c.0002.exr: cannot read rows"),
                         Error);

    std::ofstream(dir.file("d.0001.exr")) << "not an image";
    CHECK_THROWS_WITH_AS(io::SequenceReader(io::find_input_sequence(dir.file("d.####.exr")), {}),
                         doctest::Contains("d.0001.exr: cannot read image header"), Error);
}
