// `modestack compare SEQ_A SEQ_B`: idiff for frame sequences, with the
// project's quality figures. A is the sequence under test, B the reference.
// Reads both frame by frame (constant memory in the number of frames), prints a
// table of relMSE, PSNR, absolute errors, failing pixels and flicker per frame
// and for the shot, and exits with idiff's codes: 0 PASS, 1 WARNING, 2 FAILURE,
// 3 different size (idiff's ErrDifferentSize), 4 missing or unreadable input
// (idiff's ErrFile). These differ from the other subcommands' codes, so compare
// catches its own errors; bad usage is 5 and an internal error 6 so that no
// failure can be mistaken for a verdict.
#include "app/command.h"
#include "app/exr_codec_option.h"
#include "app/run_context.h"
#include "core/common/error.h"
#include "core/metrics/sequence_comparison.h"
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/layers.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <new>

namespace modestack::app {
namespace {

// idiff's exit codes (OpenImageIO idiff.cpp, enum idiffErrors), then ours.
constexpr int kExitDifferentSize = 3; // ErrDifferentSize: windows or channels differ
constexpr int kExitFile = 4;          // ErrFile: missing, unreadable input; unwritable --json
constexpr int kExitUsage = 5;         // bad command line (idiff exits 1, which would read as WARNING)
constexpr int kExitInternal = 6;      // a bug, or out of memory

struct CompareOptions {
    std::string test;
    std::string reference;
    std::vector<std::string> layers;
    std::string frames;
    metrics::PixelThresholds thresholds;
    metrics::VerdictRule rule;
    std::string json_path;
    CommonOptions common;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;
};

// The two sequences do not describe the same pixels (idiff's ErrDifferentSize).
class LayoutMismatch : public Error {
public:
    LayoutMismatch(const std::string& reason, const std::string& file)
        : Error(ErrorKind::BadInput, reason, file)
    {
    }
};

// B's files for exactly A's frames, in A's order; a frame missing in B is an error.
io::FrameSequence matching_reference(const std::string& pattern, const io::FrameSequence& test)
{
    io::FrameSequence found = io::find_input_sequence(pattern, io::describe_frames(test.frames));
    std::map<int, std::string> files;
    for (size_t i = 0; i < found.frames.size(); ++i)
        files[found.frames[i]] = found.files[i];
    found.frames = test.frames;
    found.files.clear();
    for (int frame : test.frames)
        found.files.push_back(files.at(frame));
    return found;
}

void check_windows(const io::FrameSequence& test, const io::FrameSequence& reference)
{
    for (size_t i = 0; i < test.files.size(); ++i) {
        io::FrameHeader a = io::read_frame_header(test.files[i]);
        io::FrameHeader b = io::read_frame_header(reference.files[i]);
        if (a.x != b.x || a.y != b.y || a.width != b.width || a.height != b.height)
            throw LayoutMismatch(fmt::format("data window {} differs from the reference's {} ({})",
                                             io::describe_window(a.x, a.y, a.width, a.height),
                                             io::describe_window(b.x, b.y, b.width, b.height), b.file),
                                 a.file);
    }
}

std::vector<std::string> components(const std::vector<std::string>& channel_names)
{
    std::vector<std::string> result;
    for (const std::string& name : channel_names) {
        std::string layer, component;
        io::split_channel_name(name, layer, component);
        result.push_back(component);
    }
    return result;
}

std::string number(double value, int precision = 6)
{
    if (std::isnan(value))
        return "-";
    return fmt::format("{:.{}g}", value, precision);
}

std::string table_row(const std::string& label, const metrics::ErrorSums& sums, const std::string& verdict)
{
    return fmt::format("{:>6}  {:>11}  {:>8}  {:>11}  {:>11}  {:>8}  {:>8}  {:>11}  {}\n", label,
                       number(sums.relative_mse()), number(sums.psnr(), 5), number(sums.mean_absolute()),
                       number(sums.max_absolute), number(sums.percent_failing(), 4),
                       number(sums.percent_warning(), 4), number(sums.mean_flicker()), verdict);
}

// Every figure of one set of sums; non-finite values become null in JSON.
nlohmann::ordered_json figures(const metrics::ErrorSums& sums)
{
    nlohmann::ordered_json json;
    json["relative_mse"] = sums.relative_mse();
    json["psnr_db"] = sums.psnr();
    json["tonemapped_mse"] = sums.tonemapped_mse();
    json["mean_absolute_error"] = sums.mean_absolute();
    json["max_absolute_error"] = sums.max_absolute;
    json["flicker"] = sums.mean_flicker();
    json["pixels"] = sums.pixels;
    json["pixels_failing"] = sums.pixels_failing;
    json["percent_failing"] = sums.percent_failing();
    json["pixels_warning"] = sums.pixels_warning;
    json["percent_warning"] = sums.percent_warning();
    json["non_finite"] = sums.non_finite;
    return json;
}

std::string verdict_reason(const metrics::SequenceComparison& comparison, const CompareOptions& options)
{
    int passing = comparison.frames() - comparison.frames_failing() - comparison.frames_warning();
    return fmt::format(
        "{} of {} frames fail, {} warn, {} pass (fail: more than {}% of pixels over {}{}; warn: "
        "more than {}% over {}{})",
        comparison.frames_failing(), comparison.frames(), comparison.frames_warning(), passing,
        options.rule.fail_percent, options.thresholds.fail,
        std::isinf(options.rule.hard_fail) ? "" : fmt::format(" or any over {}", options.rule.hard_fail),
        options.rule.warn_percent, options.thresholds.warn,
        std::isinf(options.rule.hard_warn) ? "" : fmt::format(" or any over {}", options.rule.hard_warn));
}

int compare(const CompareOptions& options)
{
    RunContext context(options.common);
    io::FrameSequence test = io::find_input_sequence(options.test, options.frames);
    io::FrameSequence reference = matching_reference(options.reference, test);
    check_windows(test, reference);
    if (!options.json_path.empty()) {
        std::vector<std::string> inputs = test.files;
        inputs.insert(inputs.end(), reference.files.begin(), reference.files.end());
        io::check_outputs({options.json_path}, inputs);
    }
    io::SequenceReader test_reader(test, options.layers, options.exr_codec);
    io::SequenceReader reference_reader(reference, options.layers, options.exr_codec);
    std::vector<std::string> test_channels = test_reader.selected_channel_names();
    std::vector<std::string> reference_channels = reference_reader.selected_channel_names();
    if (components(test_channels) != components(reference_channels))
        throw LayoutMismatch(fmt::format("channels {} do not match the reference's {} ({})",
                                         fmt::join(test_channels, ","), fmt::join(reference_channels, ","),
                                         reference.pattern),
                             test.pattern);

    const int width = test_reader.width(), height = test_reader.height();
    const int channels = test_reader.selected_channel_count();
    const std::int64_t pixels = static_cast<std::int64_t>(width) * height;
    std::vector<float> test_frame(static_cast<size_t>(pixels * channels));
    std::vector<float> reference_frame(test_frame.size());
    metrics::SequenceComparison comparison(pixels, channels, options.thresholds, options.rule);

    const bool table = !options.common.quiet;
    if (table) {
        std::printf("Comparing \"%s\" (test) and \"%s\" (reference)\n", test.pattern.c_str(),
                    reference.pattern.c_str());
        std::printf("channels %s vs %s; frames %s (%zu); %dx%d\n",
                    fmt::format("{}", fmt::join(test_channels, ",")).c_str(),
                    fmt::format("{}", fmt::join(reference_channels, ",")).c_str(),
                    io::describe_frames(test.frames).c_str(), test.frames.size(), width, height);
        std::printf("%s", fmt::format("{:>6}  {:>11}  {:>8}  {:>11}  {:>11}  {:>8}  {:>8}  {:>11}  {}\n",
                                      "frame", "relMSE", "PSNR dB", "mean abs", "max abs", "% fail", "% warn",
                                      "flicker", "verdict")
                              .c_str());
        std::fflush(stdout);
    }
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    context.progress().begin("comparing", test_reader.frame_count());
    for (int t = 0; t < test_reader.frame_count(); ++t) {
        throw_if_cancelled();
        test_reader.read_selected(t, 0, height, test_frame.data());
        reference_reader.read_selected(t, 0, height, reference_frame.data());
        metrics::FrameComparison frame = comparison.add_frame(test_frame.data(), reference_frame.data());
        if (table)
            std::printf("%s", table_row(std::to_string(test.frames[t]), frame.sums,
                                        metrics::verdict_name(frame.verdict))
                                  .c_str());
        nlohmann::ordered_json row;
        row["frame"] = test.frames[t];
        row.update(figures(frame.sums));
        row["verdict"] = metrics::verdict_name(frame.verdict);
        per_frame.push_back(row);
        context.progress().advance();
    }
    context.progress().end();

    metrics::Verdict verdict = comparison.verdict();
    if (table) {
        std::printf("%s", table_row("shot", comparison.shot(), metrics::verdict_name(verdict)).c_str());
        std::printf("%s\n", verdict_reason(comparison, options).c_str());
    }
    std::printf("%s\n", metrics::verdict_name(verdict));
    std::fflush(stdout);

    if (!options.json_path.empty()) {
        nlohmann::ordered_json json;
        json["version"] = version_string();
        json["command"] = command_line();
        json["test"] = test.pattern;
        json["reference"] = reference.pattern;
        json["frames"] = test.frames;
        json["frame_range"] = io::describe_frames(test.frames);
        json["width"] = width;
        json["height"] = height;
        json["test_channels"] = test_channels;
        json["reference_channels"] = reference_channels;
        json["thresholds"] = {
            {"fail", options.thresholds.fail},           {"warn", options.thresholds.warn},
            {"fail_percent", options.rule.fail_percent}, {"warn_percent", options.rule.warn_percent},
            {"hard_fail", options.rule.hard_fail},       {"hard_warn", options.rule.hard_warn}};
        json["per_frame"] = per_frame;
        nlohmann::ordered_json shot = figures(comparison.shot());
        shot["frames"] = comparison.frames();
        shot["frames_failing"] = comparison.frames_failing();
        shot["frames_warning"] = comparison.frames_warning();
        json["shot"] = shot;
        json["verdict"] = metrics::verdict_name(verdict);
        json["exit_code"] = static_cast<int>(verdict);
        io::write_text_file(options.json_path, json.dump(2) + "\n");
    }
    return static_cast<int>(verdict);
}

int fail_with(const std::string& message, int code)
{
    std::fflush(stdout);
    std::fprintf(stderr, "modestack: %s\n", message.c_str());
    return code;
}

// compare maps its own errors: main's codes (1 bad input, 2 usage, 3 internal)
// would read as WARNING, FAILURE and ErrDifferentSize here.
int run_compare(const CompareOptions& options)
{
    try {
        return compare(options);
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
    auto options = std::make_shared<CompareOptions>();
    CLI::App* command = parent.add_subcommand(
        "compare",
        "Compare a sequence with a reference like idiff: relMSE, PSNR, errors, flicker; pass/warn/fail");
    command
        ->add_option("SEQ_A", options->test, "Sequence under test: name.####.exr, name.%04d.exr, name.@.exr")
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
    command
        ->add_option("--threads", options->common.threads,
                     "Worker threads (0 = all cores); results do not depend on it")
        ->check(kNonNegative);
    command->add_flag("-q,--quiet", options->common.quiet,
                      "Print only the verdict line (no table, no progress)");
    add_exr_codec_option(*command, options->exr_codec);
    command->footer(
        "The shot's verdict is its worst frame's. Exit codes (idiff's, unlike the other subcommands): "
        "0 PASS, 1 WARNING, 2 FAILURE, 3 the sequences differ in size or channels, 4 missing or "
        "unreadable input or unwritable --json, 5 bad usage, 6 internal error, 130/143 interrupted.");
    return {command, [options] { return run_compare(*options); }, kExitUsage};
}

} // namespace modestack::app
