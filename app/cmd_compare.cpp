// `modestack compare SEQ_A SEQ_B`: the command line of idiff for frame
// sequences (compare() in app/compare_job.h). A is the sequence under test, B the reference.
// Reads both frame by frame (constant memory in the number of frames), prints a
// table of relMSE, PSNR, absolute errors, failing pixels and flicker per frame
// and for the shot, and exits with idiff's codes: 0 PASS, 1 WARNING, 2 FAILURE,
// 3 different size (idiff's ErrDifferentSize), 4 missing or unreadable input
// (idiff's ErrFile). These differ from the other subcommands' codes, so compare
// catches its own errors; bad usage is 5 and an internal error 6 so that no
// failure can be mistaken for a verdict.
#include "app/command.h"
#include "app/compare_job.h"
#include "app/exr_codec_option.h"
#include "app/run_context.h"
#include "core/common/error.h"
#include "io/text_output.h"

#include <cstdio>
#include <new>

namespace modestack::app {
namespace {

// idiff's exit codes (OpenImageIO idiff.cpp, enum idiffErrors), then ours.
constexpr int kExitDifferentSize = 3; // ErrDifferentSize: windows or channels differ
constexpr int kExitFile = 4;          // ErrFile: missing, unreadable input; unwritable --json
constexpr int kExitUsage = 5;         // bad command line (idiff exits 1, which would read as WARNING)
constexpr int kExitInternal = 6;      // a bug, or out of memory

struct CompareCommand {
    CompareJob job;
    CommonOptions common;
};

int fail_with(const std::string& message, int code)
{
    std::fflush(stdout);
    std::fprintf(stderr, "modestack: %s\n", message.c_str());
    return code;
}

// compare maps its own errors: main's codes (1 bad input, 2 usage, 3 internal)
// would read as WARNING, FAILURE and ErrDifferentSize here.
int compare_and_report(const CompareCommand& command)
{
    CompareResult result = compare(command.job, command.common);
    std::printf("%s\n", metrics::verdict_name(result.verdict));
    std::fflush(stdout);
    if (!command.job.json_path.empty())
        io::write_text_file(command.job.json_path, compare_json(result).dump(2) + "\n");
    return static_cast<int>(result.verdict);
}

int run_compare(const CompareCommand& command)
{
    try {
        return compare_and_report(command);
    } catch (const LayoutMismatch& error) {
        return fail_with(error.what(), kExitDifferentSize);
    } catch (const Error& error) {
        switch (error.kind()) {
        case ErrorKind::Cancelled:
            throw; // main exits with 128 + signal, as every subcommand does
        case ErrorKind::Usage:
            return fail_with(error.what(), kExitUsage);
        case ErrorKind::Internal:
            return fail_with(error.what(), kExitInternal);
        case ErrorKind::BadInput:
            break;
        }
        return fail_with(error.what(), kExitFile);
    } catch (const std::bad_alloc&) {
        return fail_with("out of memory", kExitInternal);
    } catch (const std::exception& error) {
        return fail_with(std::string("internal error: ") + error.what(), kExitInternal);
    }
}

// CLI11's NonNegativeNumber prints the whole double range in its message.
const CLI::Validator kNonNegative(
    [](std::string& text) {
        double value = 0;
        return CLI::detail::lexical_cast(text, value) && value >= 0 ? std::string()
                                                                    : "'" + text + "' must be a number >= 0";
    },
    "NONNEGATIVE");

} // namespace

Subcommand add_compare_command(CLI::App& parent)
{
    auto command_options = std::make_shared<CompareCommand>();
    CompareJob* options = &command_options->job;
    CLI::App* command = parent.add_subcommand(
        "compare",
        "Compare a sequence with a reference like idiff: relMSE, PSNR, errors, flicker; pass/warn/fail");
    command
        ->add_option("SEQ_A", options->test,
                     "Sequence under test: name.####.exr, name.%04d.exr, name.%d.exr (unpadded), name.@.exr")
        ->required();
    command->add_option("SEQ_B", options->reference, "Reference sequence; must hold every frame of SEQ_A")
        ->required();
    command->add_option("--layer", options->layers,
                        "Layer to compare: NAME.R/G/B or <prefix>.NAME.<ch> (Cycles DiffInd); repeatable. "
                        "Default: the only RGB layer")
        ->allow_extra_args(false);  // one value per --layer, so that `--layer DiffInd a b` works
    command->add_option("--frames", options->frames, "Only these frames: 1-48, 1001-1100, 1-100x2, 1,3,7-9");
    command
        ->add_option("--fail", options->thresholds.fail,
                     "A pixel fails when any channel differs by more than this")
        ->check(kNonNegative);
    command
        ->add_option("--warn", options->thresholds.warn,
                     "A pixel warns when any channel differs by more than this")
        ->check(kNonNegative);
    command
        ->add_option("--fail-percent", options->rule.fail_percent,
                     "A frame FAILS when more than this % of its pixels fail")
        ->check(CLI::Range(0.0, 100.0));
    command
        ->add_option("--warn-percent", options->rule.warn_percent,
                     "A frame WARNS when more than this % of its pixels warn")
        ->check(CLI::Range(0.0, 100.0));
    command->add_option("--hard-fail", options->rule.hard_fail, "A frame FAILS when any error exceeds this")
        ->check(kNonNegative);
    command->add_option("--hard-warn", options->rule.hard_warn, "A frame WARNS when any error exceeds this")
        ->check(kNonNegative);
    command->add_option("--json", options->json_path,
                        "Write every figure, per frame and for the shot, as JSON");
    add_exr_codec_option(*command, options->exr_codec);
    command
        ->add_option("--threads", command_options->common.threads,
                     "Worker threads (0 = all cores); results do not depend on it")
        ->check(kNonNegative);
    command->add_flag("-q,--quiet", command_options->common.quiet,
                      "Print only the verdict line (no table, no progress)");
    command->footer(
        "The shot's verdict is its worst frame's. Exit codes (idiff's, unlike the other subcommands): "
        "0 PASS, 1 WARNING, 2 FAILURE, 3 the sequences differ in size or channels, 4 missing or "
        "unreadable input or unwritable --json, 5 bad usage, 6 internal error, 130/143 interrupted.");
    return {command, [command_options] { return run_compare(*command_options); }, kExitUsage};
}

} // namespace modestack::app
