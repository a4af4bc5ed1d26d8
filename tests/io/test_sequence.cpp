// Frame-sequence patterns and ranges as oiiotool users write them.
#include "core/common/error.h"
#include "io/sequence.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <filesystem>

using namespace modestack;
using modestack::testkit::TempDir;

namespace {
std::string normalized(const std::string& pattern)
{
    std::string printf_pattern, range;
    REQUIRE(io::normalize_pattern(pattern, printf_pattern, range));
    return printf_pattern;
}
void touch_frames(const TempDir& dir, const std::vector<int>& frames)
{
    testkit::write_sequence(dir.file("shot.%04d.exr"), frames, {}, [](int, int, int, int) { return 1.0f; });
}
}  // namespace

TEST_CASE("patterns: #### is four digits, # is four digits, @ one digit each, %04d as is")
{
    CHECK(normalized("dir/shot.####.exr") == "dir/shot.%04d.exr");
    CHECK(normalized("shot.#.exr") == "shot.%04d.exr");
    CHECK(normalized("shot.@@@.exr") == "shot.%03d.exr");
    CHECK(normalized("shot.@.exr") == "shot.%01d.exr");
    CHECK(normalized("shot.%05d.exr") == "shot.%05d.exr");
    CHECK(normalized("shot.##.exr") == "shot.%02d.exr");
    std::string printf_pattern, range;
    CHECK(io::normalize_pattern("shot.1001-1010#.exr", printf_pattern, range));
    CHECK(range == "1001-1010");
    CHECK_FALSE(io::normalize_pattern("shot.exr", printf_pattern, range));
}

TEST_CASE("frame ranges: plain, 1001-based, stepped, lists, and malformed ones are usage errors")
{
    CHECK(io::parse_frame_range("1-5") == std::vector<int>{1, 2, 3, 4, 5});
    CHECK(io::parse_frame_range("1001-1003") == std::vector<int>{1001, 1002, 1003});
    CHECK(io::parse_frame_range("1-9x4") == std::vector<int>{1, 5, 9});
    CHECK(io::parse_frame_range("1,3,7-9") == std::vector<int>{1, 3, 7, 8, 9});
    for (const char* bad : {"", "abc", "1-", "1-3,x", "3,3"}) {
        CAPTURE(bad);
        try {
            io::parse_frame_range(bad);
            FAIL("no error");
        } catch (const Error& error) {
            CHECK(error.kind() == ErrorKind::Usage);
            CHECK(std::string(error.what()).find("--frames") != std::string::npos);
        }
    }
}

TEST_CASE("describe_frames is compact and round-trips through parse_frame_range")
{
    for (std::vector<int> frames : {std::vector<int>{1, 2, 3, 4}, {1001, 1002}, {1, 3, 5, 7}, {1, 3, 7, 8, 9}, {5}}) {
        std::string text = io::describe_frames(frames);
        CAPTURE(text);
        CHECK(io::parse_frame_range(text) == frames);
    }
    CHECK(io::describe_frames({1, 2, 3, 4}) == "1-4");
    CHECK(io::describe_frames({1, 3, 5, 7}) == "1-7x2");
}

TEST_CASE("input sequences: scanned from disk, 1001-based, gaps are an error unless --frames names the frames")
{
    TempDir dir;
    touch_frames(dir, {1001, 1002, 1003, 1005});
    io::FrameSequence chosen = io::find_input_sequence(dir.file("shot.####.exr"), "1001-1003");
    CHECK(chosen.frames == std::vector<int>{1001, 1002, 1003});
    CHECK(chosen.files.back() == dir.file("shot.1003.exr"));
    io::FrameSequence scanned = io::scan_input_sequence(dir.file("shot.####.exr"));
    CHECK(scanned.frames == std::vector<int>{1001, 1002, 1003, 1005});
    CHECK(io::missing_frames(scanned.frames) == std::vector<int>{1004});
    try {
        io::find_input_sequence(dir.file("shot.####.exr"));
        FAIL("no error for a gap");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::BadInput);
        CHECK(std::string(error.what()).find("1004") != std::string::npos);
    }
    try {
        io::find_input_sequence(dir.file("shot.%04d.exr"), "1003-1004");
        FAIL("no error for a missing frame");
    } catch (const Error& error) {
        CHECK(error.file() == dir.file("shot.1004.exr"));
        CHECK(error.frame() == 1004);
    }
    CHECK(io::find_input_sequence(dir.file("shot.####.exr"), "1001-1005x2").frames == std::vector<int>{1001, 1003, 1005});
}

TEST_CASE("input sequences: no frames, missing directory and non-patterns are clear errors")
{
    TempDir dir;
    CHECK_THROWS_AS(io::find_input_sequence(dir.file("none.####.exr")), Error);
    CHECK_THROWS_AS(io::find_input_sequence(dir.file("missing/none.####.exr")), Error);
    try {
        io::find_input_sequence(dir.file("plain.exr"));
        FAIL("no error");
    } catch (const Error& error) {
        CHECK(error.kind() == ErrorKind::Usage);
    }
}

TEST_CASE("output sequences name one file per frame with the pattern's padding")
{
    io::FrameSequence out = io::output_sequence("out/den.####.exr", {1, 2, 10});
    CHECK(out.files == std::vector<std::string>{"out/den.0001.exr", "out/den.0002.exr", "out/den.0010.exr"});
    CHECK_THROWS_AS(io::output_sequence("out/den.exr", {1, 2}), Error);
}

TEST_CASE("input sequences: a pattern without a directory is found in the current directory")
{
    TempDir dir;
    touch_frames(dir, {7, 8, 9});
    std::string previous = std::filesystem::current_path().string();
    std::filesystem::current_path(dir.path());
    io::FrameSequence found = io::find_input_sequence("shot.####.exr");
    std::filesystem::current_path(previous);
    CHECK(found.frames == std::vector<int>{7, 8, 9});
    CHECK(found.files.front() == "shot.0007.exr");
}

TEST_CASE(
    "input sequences: %d and @ find unpadded frames, %04d padded ones, whatever the directory is called")
{
    TempDir dir;
    std::filesystem::create_directory(dir.file("a (v2)+"));
    auto write = [&](const std::string& name) {
        testkit::write_exr(dir.file("a (v2)+/" + name), {}, 1, [](int, int, int, int) { return 1.0f; });
    };
    for (const char* name :
         {"u.1.exr", "u.2.exr", "u.10.exr", "u.007.exr", "u.0008.exr", "u.x9.exr", "u.-3.exr"})
        write(name);
    std::filesystem::create_directory(dir.file("a (v2)+/u.11.exr")); // a directory is not a frame
    io::FrameSequence unpadded = io::scan_input_sequence(dir.file("a (v2)+/u.%d.exr"));
    CHECK(unpadded.frames == std::vector<int>{-3, 1, 2, 10});
    CHECK(unpadded.files[2] == dir.file("a (v2)+/u.2.exr"));
    CHECK(io::scan_input_sequence(dir.file("a (v2)+/u.@.exr")).frames == std::vector<int>{-3, 1, 2, 10});
    CHECK(io::scan_input_sequence(dir.file("a (v2)+/u.%03d.exr")).frames == std::vector<int>{7});
    CHECK(io::scan_input_sequence(dir.file("a (v2)+/u.####.exr")).frames == std::vector<int>{8});
    CHECK(io::find_input_sequence(dir.file("a (v2)+/u.%d.exr"), "1-2").files.back() ==
          dir.file("a (v2)+/u.2.exr"));
    // Four digits, or more for a larger frame, as the pattern writes it.
    write("u.12345.exr");
    CHECK(io::scan_input_sequence(dir.file("a (v2)+/u.%04d.exr")).frames == std::vector<int>{8, 12345});
}

TEST_CASE("input sequences: %d without a directory, and a literal %% beside it")
{
    TempDir dir;
    for (const char* name : {"f%.3.exr", "f%.4.exr"})
        testkit::write_exr(dir.file(name), {}, 1, [](int, int, int, int) { return 1.0f; });
    std::string previous = std::filesystem::current_path().string();
    std::filesystem::current_path(dir.path());
    io::FrameSequence found = io::find_input_sequence("f%%.%d.exr");
    std::filesystem::current_path(previous);
    CHECK(found.frames == std::vector<int>{3, 4});
    CHECK(found.files.front() == "f%.3.exr");
}
