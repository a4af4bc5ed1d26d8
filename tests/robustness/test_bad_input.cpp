// The bad-input corpus (issue 12): every subcommand on broken sequences, broken
// files and out-of-range options. Each case runs the real binary and checks the
// exact exit code, that stderr is one line naming the file or option, and that
// nothing was written under a final name and no temporary file was left. The
// corpus is generated here, into a temp dir; the table of these cases and their
// messages is in docs/robustness.md. tests/e2e covers the first cases of each
// subcommand (unknown layer, size mismatch, --rank 0, ...); this adds the rest.
#include "tests/robustness/robustness_kit.h"
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/stat.h>
#include <unistd.h>

using namespace modestack;
using namespace modestack::robustness;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

constexpr int kWidth = 12, kHeight = 8;

float smooth_value(int frame, int x, int y, int c) { return 0.2f + 0.01f * x + 0.02f * y + 0.05f * c + 0.01f * frame; }

testkit::ExrLayout rgb_layout(int width = kWidth, int height = kHeight)
{
    testkit::ExrLayout layout;
    layout.width = width;
    layout.height = height;
    return layout;
}

struct Case {
    std::string arguments;  ///< after "modestack"
    int exit_code;
    std::string message;    ///< must appear in the one line on stderr
};

// Runs every case and checks the promise of issue 12; `output` is the directory
// the cases write into (it must hold neither final nor temporary files after).
void check_cases(const std::vector<Case>& cases, const std::string& output, bool remove_output = true)
{
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack(c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK_MESSAGE(one_line(result.err), result.err);
        CHECK(result.err.rfind("modestack: ", 0) == 0);
        CHECK_MESSAGE(result.err.find(c.message) != std::string::npos, result.err);
        // ROBUSTNESS_TABLE=FILE collects "arguments | exit | message" rows for docs/robustness.md.
        if (const char* table = std::getenv("ROBUSTNESS_TABLE"))
            std::ofstream(table, std::ios::app) << c.arguments << " | " << result.exit_code << " | " << result.err;
        CHECK(final_files(output).empty());
        CHECK(temporary_files(output).empty());
        std::error_code ignored;
        if (remove_output)
            std::filesystem::remove_all(output, ignored);
    }
}

const std::vector<Damage> kDamages{Damage::ZeroBytes,          Damage::BadMagic,     Damage::HeaderCut,
                                   Damage::OffsetTableCut,     Damage::OffsetTableGarbage,
                                   Damage::ChunkGarbage,       Damage::ChunkCut};

std::string damaged_name(size_t index) { return "dmg" + std::to_string(index); }

// "dmg<i>.%04d.exr", frames 1-5, frame 3 damaged as kDamages[i].
void write_damaged_sequences(const TempDir& dir)
{
    for (size_t i = 0; i < kDamages.size(); ++i) {
        std::string pattern = dir.file(damaged_name(i) + ".%04d.exr");
        testkit::write_sequence(pattern, {1, 2, 3, 4, 5}, rgb_layout(), smooth_value);
        damage_exr(frame_file(pattern, 3), kDamages[i]);
    }
}

}  // namespace

TEST_CASE("the corpus damages what it says: the layout parser finds header, offsets and chunks")
{
    TempDir dir;
    testkit::write_exr(dir.file("a.exr"), rgb_layout(kWidth, 40), 1, smooth_value);
    ExrLayoutOffsets layout = parse_exr_layout(dir.file("a.exr"));
    // ZIP packs 16 scanlines per chunk: 40 rows are 3 chunks, in increasing order after the table.
    REQUIRE(layout.chunk_offsets.size() == 3);
    CHECK(layout.chunk_offsets[0] == layout.header_end + 3 * 8);
    CHECK(layout.chunk_offsets[1] > layout.chunk_offsets[0]);
    CHECK(layout.chunk_offsets[2] < layout.file_size);
    for (Damage damage : kDamages) {
        CAPTURE(damage_name(damage));
        std::string copy = dir.file("b.exr");
        std::filesystem::copy_file(dir.file("a.exr"), copy, std::filesystem::copy_options::overwrite_existing);
        damage_exr(copy, damage);
        CHECK(read_bytes(copy) != read_bytes(dir.file("a.exr")));
    }
}

TEST_CASE("denoise: broken sequences and broken files exit 1 naming the file, nothing written")
{
    TempDir dir;
    std::vector<int> five{1, 2, 3, 4, 5};
    testkit::write_sequence(dir.file("in.%04d.exr"), five, rgb_layout(), smooth_value);
    testkit::write_sequence(dir.file("gap.%04d.exr"), {1, 2, 4, 5}, rgb_layout(), smooth_value);
    // Same size, different data window: frame 3 starts at (2, 1).
    testkit::write_sequence(dir.file("window.%04d.exr"), {1, 2, 4, 5}, rgb_layout(), smooth_value);
    write_rgb_exr(dir.file("window.0003.exr"), kWidth, kHeight, 2, 1);
    // Frame 3 lacks the B channel.
    testkit::write_sequence(dir.file("channels.%04d.exr"), {1, 2, 4, 5}, rgb_layout(), smooth_value);
    testkit::ExrLayout red_green = rgb_layout();
    red_green.channel_names = {"R", "G"};
    testkit::write_exr(dir.file("channels.0003.exr"), red_green, 3, smooth_value);
    // A directory where frame 3 should be.
    testkit::write_sequence(dir.file("folder.%04d.exr"), {1, 2, 4, 5}, rgb_layout(), smooth_value);
    std::filesystem::create_directory(dir.file("folder.0003.exr"));
    testkit::write_sequence(dir.file("single.%04d.exr"), {7}, rgb_layout(), smooth_value);
    for (int frame : five)
        write_rgb_exr(frame_file(dir.file("parts.%04d.exr"), frame), kWidth, kHeight, 0, 0, 2);
    write_damaged_sequences(dir);

    std::string out = " -q -o " + dir.file("out/d.####.exr");
    std::vector<Case> cases{
        {"denoise " + dir.file("gap.####.exr") + out, 1, "gap.####.exr: missing frames between 1 and 5: 3"},
        {"denoise " + dir.file("gap.####.exr") + " --frames 1-5" + out, 1, "gap.0003.exr: frame 3 is missing"},
        {"denoise " + dir.file("window.####.exr") + out, 1, "window.0003.exr: data window 12x8+2+1 differs"},
        {"denoise " + dir.file("channels.####.exr") + out, 1, "channels.0003.exr: channel 'B' not found"},
        {"denoise " + dir.file("folder.####.exr") + " --frames 1-5" + out, 1,
         "folder.0003.exr: is a directory, not an image file"},
        {"denoise " + dir.file("single.####.exr") + out, 1, "single.####.exr: denoising needs at least 3 frames, found 1"},
        // Multi-part files are read (tests/e2e/test_multipart_cli.cpp): parts of bare R, G, B are layers.
        {"denoise " + dir.file("parts.####.exr") + out, 1,
         "parts.0001.exr: several RGB layers; choose with --layer (layers: part0 [R,G,B], part1 [R,G,B])"},
        {"denoise " + dir.file("parts.####.exr") + " --layer part2" + out, 1,
         "parts.0001.exr: layer 'part2' not found"},
        {"denoise " + dir.file("in.####.exr") + " --layer DiffInd" + out, 1, "in.0001.exr: layer 'DiffInd' not found"},
    };
    for (size_t i = 0; i < kDamages.size(); ++i) {
        std::string file = damaged_name(i) + ".0003.exr: ";
        // Header damage is found when the frames are opened, chunk damage when their rows are read.
        bool in_chunk = kDamages[i] == Damage::OffsetTableGarbage || kDamages[i] == Damage::ChunkGarbage ||
                        kDamages[i] == Damage::ChunkCut;
        // A header cut inside an attribute is caught by the header walk, before OpenEXR.
        const char* expected = in_chunk                           ? "cannot read rows 0-7"
                               : kDamages[i] == Damage::HeaderCut  ? "damaged header"
                               : kDamages[i] == Damage::ZeroBytes ? "empty file (0 bytes)"
                                                                   : "cannot read image header";
        cases.push_back({"denoise " + dir.file(damaged_name(i) + ".####.exr") + out, 1, file + expected});
    }
    check_cases(cases, dir.file("out"));
}

TEST_CASE("denoise: the output may not be the input however it is spelled, and options out of range exit 2")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1, 2, 3, 4, 5}, rgb_layout(), smooth_value);
    std::filesystem::create_directory_symlink(dir.path(), dir.file("link"));
    std::string in = "denoise " + dir.file("in.####.exr") + " -q";
    std::string out = " -o " + dir.file("out/d.####.exr");
    std::vector<Case> cases{
        {in + " -o " + dir.file("in.%04d.exr"), 2, "is also an input"},
        {in + " -o " + dir.file("in.@@@@.exr"), 2, "is also an input"},
        {in + " -o " + dir.file("link/in.####.exr"), 2, "link/in.0001.exr' is also an input"},
        {in + " -o " + dir.file("out/../in.####.exr"), 2, "is also an input"},
        {in + " --rank 5" + out, 1, "--rank 5 needs more than 5 frames (use 1 to 4)"},
        {in + " --rank -1" + out, 2, "--rank -1: the number of modes must be at least 1"},
        {in + " --rank two" + out, 2, "--rank 'two'"},
        {in + " --rank 2x" + out, 2, "--rank '2x'"},
        {in + " --max-memory 0" + out, 2, "--max-memory '0'"},
        {in + " --max-memory -2G" + out, 2, "--max-memory '-2G'"},
        {in + " --frames 1,1,2" + out, 2, "--frames '1,1,2': frame 1 is listed twice"},
        {in + " --frames 5-x" + out, 2, "--frames '5-x'"},
        {in + " --firefly-k 0" + out, 2, "--firefly-k"},
        {in + " --sigma-radius -1" + out, 2, "--sigma-radius"},
        {in + " --mode-filter-widths 0" + out, 2, "--mode-filter-widths"},
        {in + " --mode-filter --no-mode-filter" + out, 2, "contradict"},
        {in + " --threads -1" + out, 2, "--threads"},
        {in + " -o " + dir.file("out/d.exr"), 2, "output '" + dir.file("out/d.exr") + "' has no frame token"},
        {in + " -o " + dir.file("out/d.1-5#.exr"), 2, "must not contain a frame range"},
        // A '%' that is not the frame number used to abort in OIIO's formatter (found by fuzz/frame_range).
        {in + " -o '" + dir.file("out/x%n.####.exr") + "'", 2, "x%n.####.exr' is not a frame-sequence pattern"},
        {in + " -o '" + dir.file("out/%d%d.exr") + "'", 2, "%d%d.exr' is not a frame-sequence pattern"},
        {"info '" + dir.file("in%s.####.exr") + "'", 2, "in%s.####.exr' is not a frame-sequence pattern"},
        {"render --scene orbit --frames 1 -o '" + dir.file("out/r.#%.exr") + "'", 2, "is not a frame-sequence pattern"},
        // Two frame tokens: OIIO used the first and kept "@@@@" literally, writing out1/d.@@@@.exr.
        {in + " -o '" + dir.file("out%d/d.####.exr") + "'", 2, "is not a frame-sequence pattern"},
        {in + " -o '" + dir.file("out/d.##.@@.exr") + "'", 2, "is not a frame-sequence pattern"},
    };
    check_cases(cases, dir.file("out"));
}

TEST_CASE("info, compare and refine: damaged and missing frames exit with their codes, naming the file")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1, 2, 3, 4, 5}, rgb_layout(), smooth_value);
    testkit::write_sequence(dir.file("folder.%04d.exr"), {1, 2, 4, 5}, rgb_layout(), smooth_value);
    std::filesystem::create_directory(dir.file("folder.0003.exr"));
    write_damaged_sequences(dir);
    // A denoised-looking sequence (layer DiffInd with sigma) with a damaged chunk, for refine.
    testkit::ExrLayout with_sigma = rgb_layout();
    with_sigma.channel_names = {"DiffInd.R", "DiffInd.G", "DiffInd.B", "DiffInd.sigma.R", "DiffInd.sigma.G",
                                "DiffInd.sigma.B"};
    testkit::write_sequence(dir.file("den.%04d.exr"), {1, 2, 3}, with_sigma, smooth_value);
    damage_exr(dir.file("den.0002.exr"), Damage::ChunkGarbage);
    // With the input's variance but not the spp it was rendered at.
    testkit::ExrLayout with_variance = with_sigma;
    for (const char* channel : {"DiffIndVar.R", "DiffIndVar.G", "DiffIndVar.B"})
        with_variance.channel_names.push_back(channel);
    testkit::write_sequence(dir.file("var.%04d.exr"), {1, 2, 3}, with_variance, smooth_value);

    testkit::write_sequence(dir.file("huge.%04d.exr"), {1}, rgb_layout(), smooth_value);
    damage_exr(dir.file("huge.0001.exr"), Damage::HugeAttribute);

    std::string in = dir.file("in.####.exr");
    std::vector<Case> cases{
        // OpenEXR would allocate the 1.7 GB first (found by fuzz/exr_header); io/frame_header.cpp refuses it.
        {"info " + dir.file("huge.####.exr"), 1, "huge.0001.exr: damaged header: attribute"},
        // OIIO's std::regex recursed once per character: 60 kB crashed (found by fuzz/frame_range).
        {"info " + dir.file("d." + std::string(60000, '@') + ".exr"), 2,
         "bytes long; a path has at most 4096"},
        {"render --scene switch -o " + dir.file("out/d." + std::string(60000, '#') + ".exr"), 2,
         "output '" + dir.file("out/d.").substr(0, 40)},
        {"info " + dir.file("folder.####.exr") + " --frames 1-5", 1, "folder.0003.exr: is a directory"},
        {"info " + dir.file(damaged_name(0) + ".####.exr"), 1,
         damaged_name(0) + ".0003.exr: empty file (0 bytes)"},
        {"info " + dir.file(damaged_name(1) + ".####.exr"), 1,
         damaged_name(1) + ".0003.exr: cannot read image header"},
        {"info " + dir.file(damaged_name(2) + ".####.exr"), 1,
         damaged_name(2) + ".0003.exr: damaged header: attribute"},
        // Cut or damaged after the header: the chunk offset table against the file size.
        {"info " + dir.file(damaged_name(3) + ".####.exr"), 1,
         damaged_name(3) + ".0003.exr: truncated: the file ends inside its chunk offset table"},
        {"info " + dir.file(damaged_name(4) + ".####.exr"), 1,
         damaged_name(4) + ".0003.exr: damaged chunk offset table: 1 of 1 chunks point past the end"},
        {"info " + dir.file(damaged_name(6) + ".####.exr"), 1,
         damaged_name(6) + ".0003.exr: truncated: the last chunk"},
        // Damaged data in a file of the right size: only decoding finds it.
        {"info " + dir.file(damaged_name(5) + ".####.exr") + " --check", 1,
         damaged_name(5) + ".0003.exr: cannot decode rows 0-7"},
        {"info " + in + " --frames 0-3", 1, "in.0000.exr: frame 0 is missing"},
        {"info " + in + " --json " + dir.path(), 1, dir.path()},
        {"compare " + dir.file(damaged_name(5) + ".####.exr") + " " + in + " -q", 4,
         damaged_name(5) + ".0003.exr"},
        {"compare " + in + " " + dir.file(damaged_name(0) + ".####.exr") + " -q", 4,
         damaged_name(0) + ".0003.exr"},
        {"compare " + in + " " + dir.file("folder.####.exr") + " -q", 4, "folder.0003.exr"},
        {"compare " + in + " " + in + " --warn -1" + " -q", 5, "--warn"},
        {"compare " + in + " " + in + " --json " + dir.file("out/c.json") + " --layer DiffInd" + " -q", 4,
         "DiffInd"},
        {"refine --scene switch --size 12x8 --frames 1-3 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("out/r.####.exr"),
         1, "den.0002.exr: cannot read rows"},
        // By gain refine needs the input's variance, which this sequence lacks.
        {"refine --scene switch --size 12x8 --frames 1-3 --by-gain -q --denoised " +
             dir.file("den.####.exr") + " -o " + dir.file("out/r.####.exr"),
         1, "den.0001.exr: no DiffIndVar channels (the input's variance): refine chooses pixels by gain"},
        {"refine --scene switch --size 12x8 --frames 1-3 --by-gain -q --denoised " +
             dir.file("var.####.exr") + " -o " + dir.file("out/r.####.exr"),
         1, "var.0001.exr: no modestack:spp attribute (the input's samples per pixel)"},
        {"refine --scene switch --size 12x8 --by-gain --budget 2 -q --denoised " + dir.file("var.####.exr") +
             " -o " + dir.file("out/r.####.exr"),
         2, "three ways to choose the pixels"},
        {"refine --masks-only --by-gain -q --denoised " + dir.file("var.####.exr") + " --masks " +
             dir.file("out/m.####.exr"),
         2, "--by-gain weighs the built-in re-render's samples"},
        {"refine --scene switch --size 12x8 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("out/r.####.exr") + " --threshold 0",
         2, "--threshold"},
        {"refine --scene switch --size 12x8 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("out/r.####.exr") + " --spp -1",
         2, "--spp"},
        {"refine --scene switch --size 12x8 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("out/r.####.exr") + " --budget 150",
         2, "--budget"},
        {"refine --scene nowhere --size 12x8 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("out/r.####.exr"),
         2, "unknown scene 'nowhere'"},
        {"refine --scene switch --size 12x8 -q --denoised " + dir.file("den.####.exr") + " -o " +
             dir.file("den.####.exr"),
         2, "is also an input"},
    };
    check_cases(cases, dir.file("out"));
}

TEST_CASE("render and run: options out of range exit 2, unknown scene 2, a file as output directory 1")
{
    TempDir dir;
    std::ofstream(dir.file("file")) << "not a directory";
    write_damaged_sequences(dir);
    std::string out = " -q -o " + dir.file("out/r.####.exr");
    std::string render = "render --scene orbit --size 8x8 --spp 1";
    std::vector<Case> cases{
        {"render --scene orbit --spp -1" + out, 2, "--spp"},
        {"render --scene orbit --size 1x0" + out, 2, "--size '1x0'"},
        {"render --scene orbit --size 65537x1" + out, 2, "--size '65537x1'"},
        {"render --scene orbit --size 12x" + out, 2, "--size '12x'"},
        {"render --scene orbit --size 8x8x" + out, 2, "--size '8x8x'"},
        {"render --scene orbit --max-depth 0" + out, 2, "--max-depth"},
        {"render --scene ''" + out, 2, "unknown scene ''"},
        {"render --scene Orbit" + out, 2, "unknown scene 'Orbit'"},
        {"render --scene orbit --frames 0" + out, 2, "frame 0 is outside scene 'orbit' (frames 1-48)"},
        {"render --scene orbit --frames 1-3 -q -o " + dir.file("out/r.exr"), 2, "has no frame token"},
        {render + " --frames 1 -q -o " + dir.file("file/r.####.exr"), 1, "file: output directory is a file"},
        {render + " --mask " + dir.file(damaged_name(2) + ".####.exr") + " --frames 3" + out, 1,
         damaged_name(2) + ".0003.exr"},
        {"run --scene switch --size 0x0 --frames 1-3 -q -o " + dir.file("out"), 2, "--size '0x0'"},
        {"run --scene nowhere -q -o " + dir.file("out"), 2, "unknown scene 'nowhere'"},
        {"run --scene switch --frames 1-2 -q -o " + dir.file("out"), 2, "--frames: denoising needs at least 3 frames, found 2"},
        {"run --scene switch --frames 47-50 -q -o " + dir.file("out"), 2, "frame 49 is outside scene 'switch'"},
        {"run --scene switch --spp -1 -q -o " + dir.file("out"), 2, "--spp"},
        {"run --scene switch --budget 101 -q -o " + dir.file("out"), 2, "--budget"},
    };
    check_cases(cases, dir.file("out"));
}

// run creates its json/ folder first: a file in the way is bad input naming it, not an
// internal error (exit 3, as it was before this test).
TEST_CASE("run: a file as output directory exits 1 naming it")
{
    TempDir dir;
    std::ofstream(dir.file("file")) << "not a directory";
    check_cases({{"run --scene switch --size 8x8 --frames 1-3 -q -o " + dir.file("file"), 1, "file"}}, dir.file("out"));
}

TEST_CASE("an unwritable output directory exits 1 naming it (read-only mount as root, mode 0555 otherwise)")
{
    TempDir dir;
    testkit::write_sequence(dir.file("in.%04d.exr"), {1, 2, 3}, rgb_layout(), smooth_value);
    // Root ignores permission bits: give it a read-only filesystem instead.
    TinyFilesystem read_only(dir.path(), "64k", true);
    std::string target = read_only.path();
    if (!read_only.mounted()) {
        if (geteuid() == 0) {
            testkit::report_skipped("running as root and " + read_only.why_not());
            return;
        }
        chmod(target.c_str(), 0555);
    }
    std::vector<Case> cases{
        {"denoise " + dir.file("in.####.exr") + " -q -o " + target + "/d.####.exr", 1,
         target + ": output directory is not writable"},
        {"render --scene orbit --frames 1 --size 8x8 --spp 1 -q -o " + target + "/r.####.exr", 1,
         target + ": output directory is not writable"},
        {"denoise " + dir.file("in.####.exr") + " -q -o " + target + "/sub/d.####.exr", 1,
         target + "/sub: cannot create output directory"},
        {"info " + dir.file("in.####.exr") + " --json " + target + "/i.json", 1, target + "/i.json"},
    };
    check_cases(cases, target, false);
    chmod(target.c_str(), 0755);
}

// The sequence reader (denoise, compare, refine) walks each header before OpenEXR
// would allocate a damaged attribute's claimed size (1.7 GB here), as info does.
TEST_CASE("denoise refuses a header attribute larger than the file without allocating it")
{
    TempDir dir;
    testkit::write_sequence(dir.file("huge.%04d.exr"), {1, 2, 3}, rgb_layout(), smooth_value);
    damage_exr(dir.file("huge.0002.exr"), Damage::HugeAttribute);
    check_cases({{"denoise " + dir.file("huge.####.exr") + " -q -o " + dir.file("out/d.####.exr"), 1,
                  "huge.0002.exr: damaged header: attribute"}},
                dir.file("out"));
}
