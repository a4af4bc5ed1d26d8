// End-to-end: `modestack denoise --stage stats|solve|survey|modes|write` as a farm
// job runs it, one command per task, on a generated multi-layer sequence: the
// outputs hold the same pixels, in every channel, as one `denoise` run, and a
// write task reads no frame but its own (the others are damaged on disk);
// partial files that are missing, duplicated, from another shot or solve, or
// made with other options are refused with one line and nothing written.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::read_text;
using testkit::TempDir;

namespace {
// 150 rows: blocks of 64 rows 0-63, 64-127 and 128-149.
constexpr int kWidth = 32, kHeight = 150, kFrames = 12;

testkit::ExrLayout layout()
{
    testkit::ExrLayout result;
    result.width = kWidth;
    result.height = kHeight;
    result.channel_names = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                            "ViewLayer.DiffInd.R",  "ViewLayer.DiffInd.G",  "ViewLayer.DiffInd.B"};
    result.channel_types = {"half", "half", "half", "float", "float", "float"};
    return result;
}

// DiffInd: a rank-2 signal with noise and a firefly; Combined: other data.
// `repeat`: the same noise in every frame (a fixed seed).
float noisy_value(int frame, int x, int y, int c, bool repeat)
{
    if (c < 3)
        return 0.01f * x + 0.02f * y + frame;
    std::mt19937 generator(static_cast<unsigned>((((repeat ? 1 : frame) * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.15f);
    const float t = static_cast<float>(frame) / kFrames;
    float value = 0.6f + 0.3f * std::sin(0.2f * x + c) * std::cos(0.05f * y) * (1 + t) + 0.3f * (x > 16) * t * t;
    if (frame == 4 && x == 3 && y == 100)
        value += 200.0f;
    return value + normal(generator);
}

float fresh_noise(int frame, int x, int y, int c)
{
    return noisy_value(frame, x, y, c, false);
}

std::vector<int> frames(int first, int last)
{
    std::vector<int> result;
    for (int f = first; f <= last; ++f)
        result.push_back(f);
    return result;
}

void run_ok(const std::string& arguments)
{
    auto result = run_modestack(arguments);
    REQUIRE_MESSAGE(result.exit_code == 0, arguments << "\n" << result.err);
}

// Every frame of `a` and `b` holds the same channels with the same bytes.
void check_same_pixels(const std::string& a, const std::string& b)
{
    for (int frame = 1; frame <= kFrames; ++frame) {
        char name[32];
        std::snprintf(name, sizeof name, "/d.%04d.exr", frame);
        CAPTURE(frame);
        CHECK(testkit::read_channel_names(a + name) == testkit::read_channel_names(b + name));
        CHECK(testkit::read_native(a + name) == testkit::read_native(b + name));
    }
}
}  // namespace

TEST_CASE("denoise --stage: stats, solve, survey, modes and write tasks give the pixels of one run, write "
          "reading only its frames and their reach")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), frames(1, kFrames), layout(), fresh_noise);
    // Noise that repeats: the solve task measures it once and hands the share the choice counts to the
    // writes.
    testkit::write_sequence(dir.file("rep.%04d.exr"), frames(1, kFrames), layout(),
                            [](int frame, int x, int y, int c) { return noisy_value(frame, x, y, c, true); });
    for (const auto& [method, input] :
         {std::pair<std::string, std::string>{"", "in"}, {"--no-mode-filter --rank 2 ", "in"}, {"", "rep"}}) {
        CAPTURE(method);
        CAPTURE(input);
        const std::string in = "denoise " + dir.file(input + ".####.exr") + " --layer DiffInd -q ";
        TempDir job;
        run_ok(in + method + "-o " + job.file("one/d.####.exr") + " --json " + job.file("one.json"));
        // Two statistics tasks by share, one by rows; the solve task gets them in any order.
        run_ok(in + method + "--stage stats --rows 1/2 -o " + job.file("s1.stats"));
        run_ok(in + method + "--stage stats --rows 64-127 -o " + job.file("s2.stats"));
        run_ok(in + method + "--stage stats --rows 128-149 -o " + job.file("s3.stats"));
        run_ok(in + method + "--stage solve --stats " + job.file("s3.stats") + " " + job.file("s1.stats") + " " +
               job.file("s2.stats") + " -o " + job.file("shot.solve") + " --json " + job.file("solve.json"));
        // Survey and modes tasks over other bands of rows than the statistics tasks.
        const std::string after_solve = in + method + "--solve " + job.file("shot.solve") + " ";
        run_ok(after_solve + "--stage survey --rows 0-59 -o " + job.file("1.survey"));
        run_ok(after_solve + "--stage survey --rows 60-149 -o " + job.file("2.survey"));
        const std::string surveys = "--survey " + job.file("2.survey") + " " + job.file("1.survey") + " ";
        run_ok(after_solve + surveys + "--stage modes --rows 0-40 -o " + job.file("m1.modes"));
        run_ok(after_solve + surveys + "--stage modes --rows 2/2 -o " + job.file("m2.modes") + " --json " +
               job.file("modes.json"));
        run_ok(after_solve + surveys + "--stage modes --rows 41-74 -o " + job.file("m3.modes"));
        const std::string write_all = after_solve + surveys + "--stage write --modes " + job.file("m2.modes") + " " +
                                      job.file("m1.modes") + " " + job.file("m3.modes");
        run_ok(write_all + " --frames 1/3 -o " + job.file("farm/d.####.exr"));
        // Frames 6-7 from a copy of the input whose frames 1 and 12 are damaged:
        // a write task that read more than its frames and the 4 on each side
        // that the estimator choice's spread reads would fail.
        const std::string partial = job.file("partial");
        std::filesystem::create_directories(partial);
        for (int frame = 1; frame <= kFrames; ++frame) {
            char number[16];
            std::snprintf(number, sizeof number, ".%04d.exr", frame);
            const std::string name = "/" + input + number;
            std::filesystem::copy_file(dir.file(input) + number, partial + name);
            if (frame > 1 && frame < kFrames)
                continue;
            const auto size = std::filesystem::file_size(partial + name);
            std::fstream file(partial + name, std::ios::in | std::ios::out | std::ios::binary);
            file.seekp(static_cast<std::streamoff>(size / 2));
            file << std::string(size - size / 2, '\x5a');  // the pixel chunks at the end, same size
        }
        const std::string write_partial =
            "denoise " + partial + "/" + input + ".####.exr --layer DiffInd -q " + method +
            "--stage write --solve " + job.file("shot.solve") + " " + surveys + "--modes " +
            job.file("m1.modes") + " " + job.file("m2.modes") + " " + job.file("m3.modes");
        run_ok(write_partial + " --frames 6-7 -o " + job.file("farm/d.####.exr") + " --json " +
               job.file("write.json"));
        CHECK(testkit::list_directory(job.file("farm")).size() == 6);
        CHECK(run_modestack(write_partial + " --frames 8 -o " + job.file("bad/d.####.exr")).exit_code == 1);
        run_ok(write_all + " --frames 5 -o " + job.file("farm/d.####.exr"));
        run_ok(write_all + " --frames 8-12 -o " + job.file("farm/d.####.exr"));
        check_same_pixels(job.file("one"), job.file("farm"));
        auto solve = nlohmann::json::parse(read_text(job.file("solve.json")));
        CHECK(solve["farm"]["stage"] == "solve");
        CHECK(solve["outliers"]["fireflies"].get<int>() > 0);
        auto write = nlohmann::json::parse(read_text(job.file("write.json")));
        CHECK(write["frames_written"] == 2);
        auto modes = nlohmann::json::parse(read_text(job.file("modes.json")));
        CHECK(write["rank"]["n"] == modes["rank"]["n"]);
        CHECK(write["farm"]["modes_files"].size() == 3);
        CHECK(write["farm"]["survey_files"].size() == 2);
        CHECK(modes["farm"]["rows"] == nlohmann::json::array({75, 149}));
        // What the solve measured reaches the writes through its file.
        auto one = nlohmann::json::parse(read_text(job.file("one.json")));
        auto measured = one["layers"][0]["repeating_noise"],
             handed_on = write["layers"][0]["repeating_noise"];
        CHECK(measured["repeats"] == (input == "rep"));
        CHECK(handed_on["seconds"] == 0.0); // the solve's time, not the write's
        measured.erase("seconds"), handed_on.erase("seconds");
        CHECK(handed_on == measured);
    }
}

TEST_CASE("denoise --stage: missing, duplicated, foreign and other-option partials are refused")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), frames(1, kFrames), layout(), fresh_noise);
    testkit::write_sequence(
        dir.file("other.%04d.exr"), frames(1, kFrames), layout(),
        [](int frame, int x, int y, int c) { return fresh_noise(frame, x, y, c) * 2 + 0.37f; });
    const std::string in = "denoise " + dir.file("in.####.exr") + " --layer DiffInd -q ";
    run_ok(in + "--stage stats --rows 1/2 -o " + dir.file("a1.stats"));
    run_ok(in + "--stage stats --rows 2/2 -o " + dir.file("a2.stats"));
    run_ok(in + "--stage stats --rows 1/3 -o " + dir.file("b1.stats"));
    run_ok(in + "--rank 3 --stage stats --rows 2/2 -o " + dir.file("rank3.stats"));
    run_ok(in + "--stage solve --stats " + dir.file("a1.stats") + " " + dir.file("a2.stats") + " -o " +
           dir.file("shot.solve"));
    {  // another solve of this shot: its last number changed
        std::filesystem::copy_file(dir.file("shot.solve"), dir.file("changed.solve"));
        std::fstream file(dir.file("changed.solve"), std::ios::in | std::ios::out | std::ios::binary);
        file.seekp(-1, std::ios::end);
        file.put('\x41');
    }
    run_ok(in + "--rank 2 --stage stats --rows 1/1 -o " + dir.file("rank2.stats"));
    run_ok(in + "--rank 2 --stage solve --stats " + dir.file("rank2.stats") + " -o " + dir.file("rank2.solve"));
    run_ok(in + "--stage survey --solve " + dir.file("shot.solve") + " --rows 1/1 -o " + dir.file("shot.survey"));
    run_ok(in + "--stage survey --solve " + dir.file("changed.solve") + " --rows 1/1 -o " + dir.file("changed.survey"));
    run_ok(in + "--stage survey --solve " + dir.file("shot.solve") + " --rows 0-99 -o " + dir.file("0-99.survey"));
    const std::string with_solve = in + "--solve " + dir.file("shot.solve") + " --survey " + dir.file("shot.survey") + " ";
    run_ok(with_solve + "--stage modes --rows 1/2 -o " + dir.file("m1.modes"));
    run_ok(with_solve + "--stage modes --rows 2/2 -o " + dir.file("m2.modes"));
    run_ok(with_solve + "--stage modes --rows 0-99 -o " + dir.file("m0-99.modes"));
    run_ok("denoise " + dir.file("other.####.exr") + " --layer DiffInd -q --stage stats --rows 2/2 -o " +
           dir.file("other.stats"));
    run_ok("denoise " + dir.file("in.####.exr") + " --frames 1-11 --layer DiffInd -q --stage stats --rows 2/2 -o " +
           dir.file("short.stats"));
    std::ofstream(dir.file("junk.stats")) << "not a stage file\n";
    std::ofstream(dir.file("old.stats")) << "modestack stage file 1\n{}\n";
    const std::string solve = in + "--stage solve -o " + dir.file("out/shot.solve") + " --stats ";
    struct Case {
        std::string arguments;
        int exit_code;
        std::string message;
    };
    std::vector<Case> cases{
        {solve + dir.file("a1.stats"), 1, "a1.stats: rows 64-149 are in no statistics file given"},
        {solve + dir.file("a2.stats"), 1, "a2.stats: rows 0-63 are in no statistics file given"},
        {solve + dir.file("a1.stats") + " " + dir.file("b1.stats") + " " + dir.file("a2.stats"), 1,
         "are also in"},
        {solve + dir.file("a1.stats") + " " + dir.file("other.stats"), 1,
         "other.stats: belongs to another shot"},
        {solve + dir.file("a1.stats") + " " + dir.file("short.stats"), 1,
         "short.stats: belongs to another shot"},
        {solve + dir.file("a1.stats") + " " + dir.file("rank3.stats"), 1,
         "rank3.stats: was made with other options: --rank"},
        {solve + dir.file("a1.stats") + " " + dir.file("junk.stats"), 1,
         "junk.stats: not a modestack stage file"},
        {solve + dir.file("a1.stats") + " " + dir.file("old.stats"), 1,
         "old.stats: was written by another modestack (stage file 1, this one reads 5)"},
        {solve + dir.file("a1.stats") + " " + dir.file("missing.stats"), 1, "missing.stats: cannot open"},
        {in + "--stage write --solve " + dir.file("a1.stats") + " --survey " + dir.file("shot.survey") +
             " --modes " + dir.file("m1.modes") + " -o " + dir.file("out/d.####.exr"),
         1, "a1.stats: is the output of --stage stats, not of --stage solve"},
        {in + "--stage survey --solve " + dir.file("a1.stats") + " --rows 1/2 -o " + dir.file("out/x.survey"),
         1, "a1.stats: is the output of --stage stats, not of --stage solve"},
        {with_solve + "--stage write --modes " + dir.file("m1.modes") + " -o " + dir.file("out/d.####.exr"),
         1, "m1.modes: rows 75-149 are in no modes file given"},
        {with_solve + "--stage write --modes " + dir.file("m1.modes") + " " + dir.file("m0-99.modes") + " " +
             dir.file("m2.modes") + " -o " + dir.file("out/d.####.exr"),
         1, "are also in"},
        {in + "--rank 2 --stage write --solve " + dir.file("rank2.solve") + " --survey " +
             dir.file("shot.survey") + " --modes " + dir.file("m1.modes") + " " + dir.file("m2.modes") +
             " -o " + dir.file("out/d.####.exr"),
         1, "was made with other options: --rank"},
        {with_solve + "--stage write --modes " + dir.file("m1.modes") + " " + dir.file("a2.stats") + " -o " +
             dir.file("out/d.####.exr"),
         1, "a2.stats: is the output of --stage stats, not of --stage modes"},
        {in + "--stage write --solve " + dir.file("changed.solve") + " --survey " +
             dir.file("changed.survey") + " --modes " + dir.file("m1.modes") + " " + dir.file("m2.modes") +
             " -o " + dir.file("out/d.####.exr"),
         1, "m1.modes: was made from another solve file than"},
        {with_solve + "--stage write --survey " + dir.file("changed.survey") + " --modes " +
             dir.file("m1.modes") + " " + dir.file("m2.modes") + " -o " + dir.file("out/d.####.exr"),
         1, "changed.survey: was made from another solve file than"},
        {in + "--stage modes --solve " + dir.file("shot.solve") + " --survey " + dir.file("0-99.survey") +
             " --rows 1/2 -o " + dir.file("out/x.modes"),
         1, "0-99.survey: rows 100-149 are in no survey file given"},
        {with_solve + "--stage write -o " + dir.file("out/d.####.exr"), 2,
         "--stage write needs the modes files"},
        {in + "--stage write --solve " + dir.file("shot.solve") + " --modes " + dir.file("m1.modes") +
             " -o " + dir.file("out/d.####.exr"),
         2, "--stage write needs the survey files"},
        {with_solve + "--stage modes -o " + dir.file("out/x.modes"), 2, "--stage modes needs --rows"},
        {with_solve + "--stage modes --rows 100-150 -o " + dir.file("out/x.modes"), 2,
         "the shot has rows 0-149"},
        {in + "--stage survey --solve " + dir.file("shot.solve") + " --survey " + dir.file("shot.survey") +
             " --rows 1/2 -o " + dir.file("out/x.survey"),
         2, "--survey belongs to --stage modes or write"},
        {in + "--stage stats --rows 1/2 --modes " + dir.file("m1.modes") + " -o " + dir.file("out/x.stats"),
         2, "--modes belongs to --stage write"},
        {in + "--stage stats --rows 1/2 --non-negative --non-negative-mode keep-sum -o " +
             dir.file("out/x.stats"),
         2, "--non-negative-mode keep-sum"},
        {in + "--stage stats --rows 10-63 -o " + dir.file("out/x.stats"), 2, "whole blocks of 64 rows"},
        {in + "--stage stats --rows 4/3 -o " + dir.file("out/x.stats"), 2, "--rows 4/3"},
        {in + "--stage stats --rows 1/4 -o " + dir.file("out/x.stats"), 2, "fewer than 4 tasks"},
        {in + "--stage stats -o " + dir.file("out/x.stats"), 2, "--stage stats needs --rows"},
        {in + "--stage solve --rows 1/2 -o " + dir.file("out/x.solve"), 2,
         "--rows belongs to --stage stats, survey or modes"},
        {in + "--stage stats --rows 1/2 --method rsvd -o " + dir.file("out/x.stats"), 2, "--method rsvd"},
        {in + "--stage merge -o " + dir.file("out/x.stats"), 2, "--stage 'merge'"},
        {in + "--stage stats --rows 1/2 --report r.html -o " + dir.file("out/x.stats"), 2,
         "cannot be combined with --report"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack(c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK(result.err.find('\n') == result.err.size() - 1);
        CHECK_MESSAGE(result.err.find(c.message) != std::string::npos, result.err);
        if (std::ifstream(dir.file("out")).good())
            CHECK(testkit::list_directory(dir.file("out")).empty());
    }
    // A write task's --frames must be frames of the solve file's shot.
    auto outside = run_modestack(with_solve + "--stage write --modes " + dir.file("m1.modes") + " " +
                                 dir.file("m2.modes") + " --frames 10-14 -o " +
                                 dir.file("w/d.####.exr"));
    CHECK(outside.exit_code == 2);
    CHECK_MESSAGE(outside.err.find("frame 13 is not in the shot") != std::string::npos, outside.err);
}
