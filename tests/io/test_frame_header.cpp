// io/frame_header.h: attributes found by name and read as numbers, as the
// commands that read our own attributes back (refine's modestack:spp, object
// space's modestack:points) need them.
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace modestack;
using testkit::TempDir;

TEST_CASE("frame header: attribute_value drops the type word and a string's quotes")
{
    CHECK(io::attribute_value("string \"Arnold 7.2\"") == "Arnold 7.2");
    CHECK(io::attribute_value("int 16") == "16");
    CHECK(io::attribute_value("16") == "16");
    CHECK(io::attribute_value("float2 1, 2") == "1, 2");
}

TEST_CASE("frame header: attribute_number reads the whole value, or nothing")
{
    CHECK(io::attribute_number("int 16") == 16.0);
    CHECK(io::attribute_number("float 0.25") == 0.25);
    CHECK(io::attribute_number("double -3e-2") == -0.03);
    CHECK(io::attribute_number("16") == 16.0); // no type word
    CHECK_FALSE(io::attribute_number("int 16x"));
    CHECK_FALSE(io::attribute_number("string abc"));
    CHECK_FALSE(io::attribute_number("int "));
    CHECK_FALSE(io::attribute_number(""));
    CHECK_FALSE(io::attribute_number("float nan"));
    CHECK_FALSE(io::attribute_number("float inf"));
    CHECK_FALSE(io::attribute_number("float2 1, 2")); // not its last word
}

TEST_CASE("frame header: attribute_count takes whole numbers from 1 to the largest, nothing else")
{
    CHECK(io::attribute_count("int 1", 10) == 1);
    CHECK(io::attribute_count("int 10", 10) == 10);
    CHECK(io::attribute_count("float 4", 10) == 4);
    CHECK_FALSE(io::attribute_count("int 11", 10));
    CHECK_FALSE(io::attribute_count("int 0", 10));
    CHECK_FALSE(io::attribute_count("int -3", 10));
    CHECK_FALSE(io::attribute_count("float 2.5", 10));
    CHECK_FALSE(io::attribute_count("string many", 10));
}

TEST_CASE("frame header: attributes we write are found by name and read back as the numbers written")
{
    TempDir dir;
    testkit::ExrLayout layout;
    layout.width = 5;
    layout.height = 3;
    layout.channel_names = {"R", "G", "B"};
    layout.channel_types = {"half", "half", "half"};
    testkit::write_sequence(dir.file("in.%04d.exr"), {1}, layout,
                            [](int, int x, int y, int c) { return 0.1f * (x + y + c); });
    io::SequenceReader reader(io::find_input_sequence(dir.file("in.####.exr")), {""}); // the default layer
    const std::string path = dir.file("out.0001.exr");
    {
        io::FrameOutput output(path, reader, 0, {},
                               {io::HeaderAttribute::of_integer("modestack:spp", 64),
                                io::HeaderAttribute::of_real("modestack:point_spacing", 0.0125),
                                io::HeaderAttribute::of_text("modestack:command", "modestack test 12")});
        std::vector<unsigned char> native;
        reader.read_native(0, 0, 3, native);
        const std::vector<float> replaced(5 * 3 * 3, 0.5f);
        output.write_replaced_rows(0, 3, native, replaced.data(), nullptr);
        output.commit();
    }
    const io::FrameHeader header = io::read_frame_header(path);
    const auto spp = io::find_attribute(header, "modestack:spp");
    REQUIRE(spp);
    CHECK(io::attribute_number(*spp) == 64.0);
    const auto spacing = io::find_attribute(header, "modestack:point_spacing");
    REQUIRE(spacing);
    REQUIRE(io::attribute_number(*spacing));
    CHECK(std::abs(*io::attribute_number(*spacing) - 0.0125) < 1e-9); // a float attribute: 7 digits
    const auto command = io::find_attribute(header, "modestack:command");
    REQUIRE(command);
    CHECK(command->find("modestack test 12") != std::string::npos);
    CHECK_FALSE(io::find_attribute(header, "modestack:absent"));
}
