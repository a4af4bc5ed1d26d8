// Outputs keep every input channel bit-exactly, their pixel types and the header
// attributes; only commit() makes a final-named file.
#include "core/common/error.h"
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/temporary_file.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <Imath/half.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

using namespace modestack;
using testkit::TempDir;

namespace {
testkit::ExrLayout multilayer()
{
    testkit::ExrLayout layout;
    layout.width = 19;
    layout.height = 7;
    layout.channel_names = {"R", "G", "B", "A", "diffuse_indirect.R", "diffuse_indirect.G", "diffuse_indirect.B", "Z"};
    layout.channel_types = {"half", "half", "half", "half", "half", "half", "half", "float"};
    layout.attributes = {{"renderer", "test"}, {"Frame", "0001"}};
    return layout;
}
float noise_value(int frame, int x, int y, int c) { return std::sin(1.7f * x + 2.3f * y + 0.9f * c + 3.1f * frame) * 5; }
}  // namespace

TEST_CASE("round trip: replaced channels change, pass-through channels are bit-exact, attributes kept")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1, 2}, multilayer(), noise_value);
    io::SequenceReader reader(io::find_input_sequence(dir.file("in.####.exr")), {"diffuse_indirect"});
    std::string path = dir.file("out.0001.exr");
    {
        io::FrameOutput output(path, reader, 0, {"diffuse_indirect.sigma.R", "diffuse_indirect.sigma.G",
                                                 "diffuse_indirect.sigma.B"},
                               {io::HeaderAttribute::of_text("modestack:command", "modestack test"),
                                io::HeaderAttribute::of_integer("modestack:rank", 3)});
        std::vector<unsigned char> native;
        for (int row = 0; row < 7; row += 3) {
            int end = std::min(7, row + 3);
            reader.read_native(0, row, end, native);
            std::vector<float> replaced(19 * (end - row) * 3, 0.5f), extra(19 * (end - row) * 3, 0.125f);
            output.write_replaced_rows(row, end, native, replaced.data(), extra.data());
        }
        output.commit();
    }
    std::vector<std::string> names = testkit::read_channel_names(path);
    CHECK(names.size() == 11);
    std::vector<std::string> kept{"R", "G", "B", "A", "Z"};
    CHECK(testkit::read_channels(path, kept) == testkit::read_channels(dir.file("in.0001.exr"), kept));
    for (float value : testkit::read_channels(path, {"diffuse_indirect.R", "diffuse_indirect.B"}))
        CHECK(value == 0.5f);
    for (float value : testkit::read_channels(path, {"diffuse_indirect.sigma.G"}))
        CHECK(value == 0.125f);
    CHECK(testkit::read_string_attribute(path, "renderer") == "test");
    CHECK(testkit::read_string_attribute(path, "modestack:command") == "modestack test");
    CHECK(testkit::read_string_attribute(path, "compression") == "zip");

    // Bit-exact: half channels are compared as raw bits, not values.
    std::vector<unsigned char> in = testkit::read_native(dir.file("in.0001.exr"));
    std::vector<unsigned char> out = testkit::read_native(path);
    // Input pixel: 7 half + 1 float = 18 bytes; output adds 3 half = 24 bytes.
    for (size_t p = 0; p < 19 * 7; ++p)
        CHECK(std::memcmp(in.data() + p * 18, out.data() + p * 24, 8) == 0);  // R,G,B,A
}

TEST_CASE("an output whose channels are all replaced needs no input rows")
{
    TempDir dir;
    testkit::ExrLayout rgb = multilayer();
    rgb.channel_names = {"R", "G", "B"};
    rgb.channel_types = {"half", "half", "half"};
    testkit::write_sequence(dir.file("in.%04d.exr"), {1}, rgb, noise_value);
    io::SequenceReader reader(io::find_input_sequence(dir.file("in.####.exr")), {});  // the unnamed layer
    CHECK(reader.selected_channel_count() == 3);
    {
        io::FrameOutput output(dir.file("out.0001.exr"), reader, 0, {"sigma.R", "sigma.G", "sigma.B"}, {});
        CHECK_FALSE(output.needs_input_rows());
        std::vector<float> replaced(19 * 7 * 3), extra(19 * 7 * 3, 0.25f);
        for (size_t i = 0; i < replaced.size(); ++i)
            replaced[i] = 0.5f * static_cast<float>(i % 11);
        output.write_replaced_rows(0, 7, std::vector<unsigned char>{}, replaced.data(), extra.data());
        output.commit();
    }
    std::vector<float> written = testkit::read_channels(dir.file("out.0001.exr"), {"R", "G", "B"});
    for (size_t i = 0; i < written.size(); ++i)
        CHECK(written[i] == 0.5f * static_cast<float>(i % 11));  // exact in half
    for (float value : testkit::read_channels(dir.file("out.0001.exr"), {"sigma.G"}))
        CHECK(value == 0.25f);
}

TEST_CASE("atomic write: nothing under the final name until commit, no temporary left after a failure")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1}, multilayer(), noise_value);
    io::SequenceReader reader(io::find_input_sequence(dir.file("in.####.exr")), {"diffuse_indirect"});
    {
        io::FrameOutput output(dir.file("out.0001.exr"), reader, 0, {}, {});
        std::vector<unsigned char> native;
        reader.read_native(0, 0, 3, native);
        std::vector<float> replaced(19 * 3 * 3, 1.0f);
        output.write_replaced_rows(0, 3, native, replaced.data(), nullptr);
        CHECK_FALSE(std::filesystem::exists(dir.file("out.0001.exr")));
        // Destroyed without commit, as when an error or interrupt unwinds.
    }
    CHECK(testkit::list_directory(dir.path()) == std::vector<std::string>{"in.0001.exr"});
}

namespace {

// The pid of a process that has exited and been reaped.
long gone_pid()
{
    pid_t child = fork();
    if (child == 0)
        _exit(0);
    int status = 0;
    waitpid(child, &status, 0);
    return child;
}

std::string this_host()
{
    char buffer[256] = {};
    gethostname(buffer, sizeof buffer - 1);
    return buffer;
}

void touch(const std::string& path) { std::ofstream(path) << "partial"; }

}  // namespace

TEST_CASE("a killed run's temporaries are removed by the next output into the directory, nobody else's")
{
    TempDir dir;
    long gone = gone_pid();
    std::string host = this_host();
    std::string dead_here = fmt::format(".out.0001.exr.{}.{}-3.modestack-tmp", host, gone);
    std::string dead_text = fmt::format(".run.json.{}.{}-0.modestack-tmp", host, gone);
    std::string alive_here = fmt::format(".out.0002.exr.{}.{}-0.modestack-tmp", host, getpid());
    std::string other_host = fmt::format(".out.0003.exr.{}x.{}-0.modestack-tmp", host, gone);
    std::string not_ours = fmt::format(".out.0004.exr.{}.{}.modestack-tmp", host, gone);  // no -N
    for (const std::string& name : {dead_here, dead_text, alive_here, other_host, not_ours})
        touch(dir.file(name));

    io::NewImageDescription image;
    image.width = 2;
    image.height = 2;
    image.channel_names = {"R", "G", "B"};
    image.channel_types = {"half", "half", "half"};
    std::vector<float> pixels(12, 0.5f);
    io::FrameOutput output(dir.file("new.exr"), image, {});
    output.write_float_rows(0, 2, pixels.data());
    output.commit();

    std::vector<std::string> left = testkit::list_directory(dir.path());
    CHECK(std::find(left.begin(), left.end(), dead_here) == left.end());
    CHECK(std::find(left.begin(), left.end(), dead_text) == left.end());
    for (const std::string& kept : {alive_here, other_host, not_ours, std::string("new.exr")})
        CHECK_MESSAGE(std::find(left.begin(), left.end(), kept) != left.end(), kept);
    CHECK(left.size() == 4);

    // Once per directory per process: a second output does not scan again.
    touch(dir.file(dead_here));
    CHECK(io::remove_stale_temporaries(dir.file("other.exr")) == 0);
    TempDir fresh;
    touch(fresh.file(dead_here));
    CHECK(io::remove_stale_temporaries(fresh.file("other.exr")) == 1);
    CHECK(testkit::list_directory(fresh.path()).empty());
}

TEST_CASE("temporary names are hidden, next to the final file, and unique")
{
    std::string first = io::temporary_path_for("/shots/a/out.0001.exr");
    std::string second = io::temporary_path_for("/shots/a/out.0001.exr");
    CHECK(first != second);
    CHECK(first.rfind("/shots/a/.out.0001.exr.", 0) == 0);
    CHECK(first.size() > 14);
    CHECK(first.compare(first.size() - 14, 14, ".modestack-tmp") == 0);
}

TEST_CASE("new images: float and half channels written from float data")
{
    TempDir dir;
    io::NewImageDescription image;
    image.width = 5;
    image.height = 4;
    image.channel_names = {"Combined.R", "Combined.G", "Combined.B", "Combined.A", "Depth.Z"};
    image.channel_types = {"half", "half", "half", "half", "float"};
    std::vector<float> pixels(5 * 4 * 5);
    for (size_t i = 0; i < pixels.size(); ++i)
        pixels[i] = 0.001f * i + 1.0f / 3.0f;
    io::FrameOutput output(dir.file("new.exr"), image, {io::HeaderAttribute::of_integer("modestack:spp", 4)});
    output.write_float_rows(0, 4, pixels.data());
    output.commit();
    std::vector<float> depth = testkit::read_channels(dir.file("new.exr"), {"Depth.Z"});
    std::vector<float> red = testkit::read_channels(dir.file("new.exr"), {"Combined.R"});
    for (size_t p = 0; p < 20; ++p) {
        CHECK(depth[p] == pixels[p * 5 + 4]);
        CHECK(red[p] == float(Imath::half(pixels[p * 5])));
    }
}

TEST_CASE("check_outputs refuses an output equal to an input and an output directory that cannot exist")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1}, multilayer(), noise_value);
    CHECK_THROWS_WITH_AS(io::check_outputs({dir.path() + "/./in.0001.exr"}, {dir.file("in.0001.exr")}),
                         doctest::Contains("is also an input"), Error);
    CHECK_THROWS_WITH_AS(io::check_outputs({dir.file("in.0001.exr") + "/sub/out.exr"}, {}),
                         doctest::Contains("output directory"), Error);
    io::check_outputs({dir.file("new/dir/out.0001.exr")}, {dir.file("in.0001.exr")});
    CHECK(std::filesystem::is_directory(dir.file("new/dir")));
}

TEST_CASE(
    "buffer bytes: libdeflate's paths hold no decode buffer per input and one chunk per output, OpenEXR's "
    "three chunks")
{
    TempDir dir;
    testkit::ExrLayout layout = multilayer(); // 18 bytes a pixel, 24 with 3 half sigma channels
    const std::vector<std::string> sigma{"diffuse_indirect.sigma.R", "diffuse_indirect.sigma.G",
                                         "diffuse_indirect.sigma.B"};
    testkit::write_sequence(dir.file("zip.%04d.exr"), {1}, layout, noise_value);
    layout.compression = "piz";
    testkit::write_sequence(dir.file("piz.%04d.exr"), {1}, layout, noise_value);

    io::SequenceReader zip(io::find_input_sequence(dir.file("zip.####.exr")), {"diffuse_indirect"});
    CHECK(zip.decoder_buffer_bytes(0) == 0);
    CHECK(io::copy_buffer_bytes(zip, 0, sigma, io::ExrCodec::Libdeflate) == 24 * 19 * 16);
    io::OutputFormat zips;
    zips.compression = "zips";
    CHECK(io::copy_buffer_bytes(zip, 0, sigma, io::ExrCodec::Libdeflate, io::PartLayout::AsInput, zips) ==
          24 * 19 * 1);
    // Through OpenImageIO, OpenEXR's library holds three chunks of the input's height.
    io::SequenceReader zip_by_oiio(io::find_input_sequence(dir.file("zip.####.exr")), {"diffuse_indirect"},
                                   io::ExrCodec::OpenImageIO);
    CHECK(zip_by_oiio.decoder_buffer_bytes(0) == 3 * 18 * 19 * 16);
    CHECK(io::copy_buffer_bytes(zip_by_oiio, 0, sigma, io::ExrCodec::OpenImageIO) == 3 * 24 * 19 * 16);

    io::SequenceReader piz(io::find_input_sequence(dir.file("piz.####.exr")), {"diffuse_indirect"});
    CHECK(piz.decoder_buffer_bytes(0) == 3 * 18 * 19 * 32);
    CHECK(io::copy_buffer_bytes(piz, 0, sigma, io::ExrCodec::Libdeflate) == 3 * 24 * 19 * 32);
    // A PIZ input written as ZIP goes through OpenImageIO too (the libdeflate writer copies ZIP inputs).
    io::OutputFormat as_zip;
    as_zip.compression = "zip";
    CHECK(io::copy_buffer_bytes(piz, 0, sigma, io::ExrCodec::Libdeflate, io::PartLayout::AsInput, as_zip) ==
          3 * 24 * 19 * 32);
}
