// `modestack info SEQ`: what a sequence holds, like exrheader for a whole shot:
// the frames found (range, count, gaps), whether each is whole, data and display
// windows, channels grouped by layer with pixel types (every part's), compression
// and header attributes, and which frames disagree with the first. Every frame's
// chunk offset tables are checked against its size; `--check` decodes every
// chunk. A bad frame gets one line on stderr naming the file and the problem,
// all of them after all frames are checked, and exit 1. `--json FILE` writes the
// same facts.
#include "app/command.h"
#include "app/info_description.h"
#include "app/info_job.h"
#include "core/common/error.h"
#include "io/text_output.h"

#include <cstdio>

namespace modestack::app {
namespace {

struct InfoOptions {
    std::string pattern;
    std::string frames;
    std::string json_path;
    bool check = false;
    bool all_attributes = false;
};

int run_info(const InfoOptions& options)
{
    io::FrameSequence sequence = options.frames.empty() ? io::scan_input_sequence(options.pattern)
                                                        : io::find_input_sequence(options.pattern, options.frames);
    InfoFindings findings =
        check_sequence(sequence, options.check ? FrameCheckDepth::EveryChunk : FrameCheckDepth::ChunkTables);
    print_info(findings, options.all_attributes);
    if (!options.json_path.empty())
        io::write_text_file(options.json_path, info_json(findings).dump(2) + "\n");
    std::fflush(stdout);
    bool all_whole = true;
    for (const CheckedFrame& frame : findings.frames)
        if (!frame.problem.empty()) {
            // As main() prints any other bad-input error.
            std::fprintf(stderr, "modestack: %s\n",
                         Error(ErrorKind::BadInput, frame.problem, frame.file).what());
            all_whole = false;
        }
    return all_whole ? 0 : exit_code(ErrorKind::BadInput);
}

}  // namespace

Subcommand add_info_command(CLI::App& parent)
{
    auto options = std::make_shared<InfoOptions>();
    CLI::App* command = parent.add_subcommand(
        "info",
        "Describe a frame sequence: frames and gaps, whether each is whole, windows, channels by layer "
        "(every part's), pixel types, attributes");
    command
        ->add_option(
            "SEQ", options->pattern,
            "Frame-sequence pattern: name.####.exr, name.%04d.exr, name.%d.exr (unpadded), name.@.exr")
        ->required();
    command->add_option("--frames", options->frames, "Only these frames: 1-48, 1001-1100, 1-100x2, 1,3,7-9");
    command->add_option("--json", options->json_path, "Also write the description as JSON to this file");
    command->add_flag(
        "--check", options->check,
        "Decode every chunk of every frame (slower): finds damaged data, not only truncated files");
    command->add_flag("--all-attributes", options->all_attributes, "Print long attribute values in full");
    return {command, [options] { return run_info(*options); }};
}

}  // namespace modestack::app
