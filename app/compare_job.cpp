// `modestack compare` as a library call (compare_job.h): idiff for frame
// sequences, with the project's quality figures. Reads both sequences frame by
// frame (constant memory in the number of frames).
#include "app/compare_job.h"

#include "app/command.h"
#include "core/common/error.h"
#include "io/frame_header.h"
#include "io/frame_output.h"
#include "io/layers.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <map>

namespace modestack::app {
namespace {

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

std::string verdict_reason(const metrics::SequenceComparison& comparison, const CompareJob& options)
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

}  // namespace

CompareResult compare(const CompareJob& job, const CommonOptions& context_options)
{
    RunContext context(context_options);
    io::FrameSequence test = io::find_input_sequence(job.test, job.frames);
    io::FrameSequence reference = matching_reference(job.reference, test);
    check_windows(test, reference);
    if (!job.json_path.empty()) {
        std::vector<std::string> inputs = test.files;
        inputs.insert(inputs.end(), reference.files.begin(), reference.files.end());
        io::check_outputs({job.json_path}, inputs);
    }
    io::SequenceReader test_reader(test, job.layers, job.exr_codec);
    io::SequenceReader reference_reader(reference, job.layers, job.exr_codec);
    CompareResult result;
    result.test_channels = test_reader.selected_channel_names();
    result.reference_channels = reference_reader.selected_channel_names();
    const std::vector<std::string>& test_channels = result.test_channels;
    const std::vector<std::string>& reference_channels = result.reference_channels;
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
    metrics::SequenceComparison comparison(pixels, channels, job.thresholds, job.rule);

    const bool table = !context_options.quiet;
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
        result.per_frame.push_back({test.frames[t], frame});
        context.progress().advance();
    }
    context.progress().end();

    result.verdict = comparison.verdict();
    if (table) {
        std::printf("%s", table_row("shot", comparison.shot(), metrics::verdict_name(result.verdict)).c_str());
        std::printf("%s\n", verdict_reason(comparison, job).c_str());
    }
    result.test = test.pattern;
    result.reference = reference.pattern;
    result.frames = test.frames;
    result.width = width;
    result.height = height;
    result.thresholds = job.thresholds;
    result.rule = job.rule;
    result.shot = comparison.shot();
    result.frames_failing = comparison.frames_failing();
    result.frames_warning = comparison.frames_warning();
    return result;
}

nlohmann::ordered_json compare_json(const CompareResult& result)
{
    nlohmann::ordered_json per_frame = nlohmann::ordered_json::array();
    for (const ComparedFrame& frame : result.per_frame) {
        nlohmann::ordered_json row;
        row["frame"] = frame.frame;
        row.update(figures(frame.comparison.sums));
        row["verdict"] = metrics::verdict_name(frame.comparison.verdict);
        per_frame.push_back(row);
    }
    nlohmann::ordered_json json;
    json["version"] = version_string();
    json["command"] = command_line();
    json["test"] = result.test;
    json["reference"] = result.reference;
    json["frames"] = result.frames;
    json["frame_range"] = io::describe_frames(result.frames);
    json["width"] = result.width;
    json["height"] = result.height;
    json["test_channels"] = result.test_channels;
    json["reference_channels"] = result.reference_channels;
    json["thresholds"] = {
        {"fail", result.thresholds.fail},           {"warn", result.thresholds.warn},
        {"fail_percent", result.rule.fail_percent}, {"warn_percent", result.rule.warn_percent},
        {"hard_fail", result.rule.hard_fail},       {"hard_warn", result.rule.hard_warn}};
    json["per_frame"] = per_frame;
    nlohmann::ordered_json shot = figures(result.shot);
    shot["frames"] = static_cast<int>(result.per_frame.size());  // comparison.frames()
    shot["frames_failing"] = result.frames_failing;
    shot["frames_warning"] = result.frames_warning;
    json["shot"] = shot;
    json["verdict"] = metrics::verdict_name(result.verdict);
    json["exit_code"] = static_cast<int>(result.verdict);
    return json;
}

}  // namespace modestack::app
