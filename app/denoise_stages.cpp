#include "app/denoise_stages.h"

#include "core/common/error.h"
#include "io/text_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <regex>
#include <set>
#include <tuple>
#include <utility>

namespace modestack::app {
namespace {

denoise::Stage parse_stage(const std::string& name)
{
    for (denoise::Stage stage : {denoise::Stage::Statistics, denoise::Stage::Solve, denoise::Stage::Survey,
                                 denoise::Stage::Modes, denoise::Stage::Write})
        if (name == denoise::stage_name(stage))
            return stage;
    throw usage_error(fmt::format("--stage '{}' is not one of stats, solve, survey, modes, write", name));
}

// "I/K" (1 ≤ I ≤ K): task I of K equal shares; false when `text` is not of that form.
bool parse_share(const std::string& text, const std::string& option, int& index, int& count)
{
    std::smatch match;
    if (!std::regex_match(text, match, std::regex(R"((\d+)/(\d+))")))
        return false;
    index = std::stoi(match[1]);
    count = std::stoi(match[2]);
    if (count < 1 || index < 1 || index > count)
        throw usage_error(fmt::format("{} {}: write I/K with 1 <= I <= K", option, text));
    return true;
}

// Share `index` of `count` of `items` things, in order: [begin, end).
std::pair<int, int> share_of(int items, int index, int count)
{
    const auto at = [&](int k) { return static_cast<int>(static_cast<std::int64_t>(items) * k / count); };
    return {at(index - 1), at(index)};
}

// Rows [begin, end) of --rows `text` in a shot of `height` rows: Y0-Y1
// (inclusive), or share I of K of the shot's units of `unit_rows` rows (1, or
// the statistics' blocks).
std::pair<int, int> parse_rows(const std::string& text, int height, int unit_rows)
{
    int index = 0, count = 0;
    std::smatch match;
    if (parse_share(text, "--rows", index, count)) {
        const int units = (height + unit_rows - 1) / unit_rows;
        if (count > units)
            throw usage_error(unit_rows == 1
                                  ? fmt::format("--rows {}: the shot has {} rows, fewer than {} tasks", text, height,
                                                count)
                                  : fmt::format("--rows {}: the shot's {} rows make {} blocks of {}, fewer than {} "
                                                "tasks",
                                                text, height, units, unit_rows, count));
        auto [begin, end] = share_of(units, index, count);
        return {begin * unit_rows, std::min(height, end * unit_rows)};
    }
    if (std::regex_match(text, match, std::regex(R"((\d+)-(\d+))")))
        return {std::stoi(match[1]), std::stoi(match[2]) + 1};
    throw usage_error(fmt::format("--rows '{}': write Y0-Y1 or I/K", text));
}

// The options that must agree between the tasks of a job: those given on the
// command line, but not where the files are, what the task does, how fast or
// how verbosely (none of which change a bit of the result).
nlohmann::ordered_json method_options_given(const CLI::App& command)
{
    static const std::set<std::string> excluded{"SEQ", "--output", "--stage", "--rows", "--stats", "--solve",
                                                "--survey", "--modes", "--frames", "--json", "--threads",
                                                "--quiet", "--max-memory", "--skip-existing", "--report",
                                                "--save-modes", "--help",
                                                // how frames are written, not what is computed
                                                "--compression", "--data-type", "--only-denoised"};
    nlohmann::ordered_json options = nlohmann::ordered_json::object();
    for (const CLI::Option* option : command.get_options())
        if (option->count() > 0 && !excluded.count(option->get_name()))
            options[option->get_name()] = option->results();
    return options;
}

nlohmann::ordered_json shot_json(const io::FrameSequence& input, const io::SequenceReader& reader)
{
    nlohmann::ordered_json files = nlohmann::ordered_json::array();
    for (const std::string& file : input.files)
        files.push_back({std::filesystem::path(file).filename().string(), std::filesystem::file_size(file)});
    return {{"frames", io::describe_frames(input.frames)},
            {"files", files},
            {"width", reader.width()},
            {"height", reader.height()},
            {"channels", reader.selected_channel_names()}};
}

}  // namespace

void add_stage_options(CLI::App& command, StageOptions& options)
{
    command.add_option(
        "--stage", options.stage,
        "Run one farm task of the denoise (README, farm jobs), in this order: stats (-o the "
        "statistics of --rows), solve (-o the temporal modes from every --stats file), survey (-o "
        "the mode filter's sums of --rows), modes (-o the mode images of --rows) and write (the "
        "outputs of --frames, reading only those frames and, with input among --estimators, the 4 "
        "on each side); the outputs are byte-identical to one "
        "run with the same options");
    command.add_option("--rows", options.rows,
                       "--stage stats, survey and modes: the rows of this task, Y0-Y1 (inclusive; for stats Y0 a "
                       "multiple of 64, Y1 + 1 too or the last row) or I/K (share I of K)");
    command.add_option("--stats", options.stats, "--stage solve: every statistics file of the shot, once");
    command.add_option("--solve", options.solve, "--stage survey, modes and write: the solve task's file");
    command.add_option("--survey", options.survey, "--stage modes and write: every survey file of the shot, once");
    command.add_option("--modes", options.modes, "--stage write: every modes file of the shot, once");
}

StageRun::StageRun(const StageOptions& options, const CLI::App& command)
    : m_options(options), m_command(command), m_stage(parse_stage(options.stage))
{
    const std::string name = denoise::stage_name(m_stage);
    const denoise::Stage stage = m_stage;
    const StageFilesInMemory* in_memory = options.in_memory.get();
    const bool by_rows = stage == denoise::Stage::Statistics || stage == denoise::Stage::Survey ||
                         stage == denoise::Stage::Modes;
    const bool after_solve = stage == denoise::Stage::Survey || stage == denoise::Stage::Modes ||
                             stage == denoise::Stage::Write;
    const bool after_survey = stage == denoise::Stage::Modes || stage == denoise::Stage::Write;
    if (!options.rows.empty() && !by_rows)
        throw usage_error(fmt::format("--rows belongs to --stage stats, survey or modes, not --stage {}", name));
    if (!options.stats.empty() && stage != denoise::Stage::Solve)
        throw usage_error(fmt::format("--stats belongs to --stage solve, not --stage {}", name));
    if (!options.solve.empty() && !after_solve)
        throw usage_error(fmt::format("--solve belongs to --stage survey, modes or write, not --stage {}", name));
    if (!options.survey.empty() && !after_survey)
        throw usage_error(fmt::format("--survey belongs to --stage modes or write, not --stage {}", name));
    if (!options.modes.empty() && stage != denoise::Stage::Write)
        throw usage_error(fmt::format("--modes belongs to --stage write, not --stage {}", name));
    if (by_rows && options.rows.empty())
        throw usage_error(fmt::format("--stage {} needs --rows Y0-Y1 or --rows I/K", name));
    if (stage == denoise::Stage::Solve && options.stats.empty() && !in_memory)
        throw usage_error("--stage solve needs the statistics files of the shot: --stats FILE...");
    if (after_solve && options.solve.empty() && !in_memory)
        throw usage_error(fmt::format("--stage {} needs the solve task's file: --solve FILE", name));
    if (after_survey && options.survey.empty() && !in_memory)
        throw usage_error(fmt::format("--stage {} needs the survey files of the shot: --survey FILE...", name));
    if (stage == denoise::Stage::Write && options.modes.empty() && !in_memory)
        throw usage_error("--stage write needs the modes files of the shot: --modes FILE...");
    for (const char* option : {"--report", "--save-modes", "--rank-map", "--segments", "--train-frames"})
        if (command.count(option) > 0)
            throw usage_error(fmt::format("--stage cannot be combined with {}: run it on one machine", option));
    if (command.count("--non-negative-mode") > 0 &&
        command.get_option("--non-negative-mode")->as<std::string>() == "keep-sum")
        throw usage_error("--stage cannot be combined with --non-negative-mode keep-sum: it needs every frame of a "
                          "pixel at once (use clamp, or run on one machine)");
    if (in_memory) {
        m_statistics_files = in_memory->stats;
        if (in_memory->solve)
            m_solve_file = *in_memory->solve;
        m_survey_files = in_memory->survey;
        m_modes_bytes = std::move(m_options.in_memory->modes);
    }
    for (const std::string& path : options.stats)
        m_statistics_files.push_back(io::read_stage_bytes(path));
    if (!options.solve.empty())
        m_solve_file = io::read_stage_bytes(options.solve);
    for (const std::string& path : options.survey)
        m_survey_files.push_back(io::read_stage_bytes(path));
    for (const std::string& path : options.modes)
        m_modes_bytes.push_back(io::read_stage_bytes(path));
}

std::string StageRun::shot_frames(const std::string& frames_option) const
{
    return writes_frames() ? io::shot_frames_of_solve_file(m_solve_file) : frames_option;
}

void StageRun::keep_written_frames(const std::string& frames_option, const std::vector<int>& shot,
                                  std::vector<std::string>& paths) const
{
    std::vector<bool> written(shot.size(), frames_option.empty());
    int index = 0, count = 0;
    if (parse_share(frames_option, "--frames", index, count)) {
        auto [begin, end] = share_of(static_cast<int>(shot.size()), index, count);
        std::fill(written.begin() + begin, written.begin() + end, true);
    } else if (!frames_option.empty()) {
        for (int frame : io::parse_frame_range(frames_option)) {
            auto at = std::find(shot.begin(), shot.end(), frame);
            if (at == shot.end())
                throw usage_error(fmt::format("--frames {}: frame {} is not in the shot of {} ({})", frames_option,
                                              frame, m_solve_file.name, io::describe_frames(shot)));
            written[static_cast<size_t>(at - shot.begin())] = true;
        }
    }
    for (size_t t = 0; t < paths.size(); ++t)
        if (!written[t])
            paths[t].clear();
}

void StageRun::prepare(const io::FrameSequence& input, const io::SequenceReader& reader)
{
    m_fingerprint = {shot_json(input, reader), method_options_given(m_command)};
    const int height = reader.height(), frames = static_cast<int>(input.frames.size());
    switch (m_stage) {
    case denoise::Stage::Survey:
    case denoise::Stage::Modes:  // any rows: their sums and images do not depend on the bands
        std::tie(m_row_begin, m_row_end) = parse_rows(m_options.rows, height, 1);
        // Checked here too, before any input is read (the task checks again).
        denoise::check_task_rows(m_row_begin, m_row_end, height);
        m_solved = io::read_solve(m_solve_file, m_fingerprint);
        if (m_stage == denoise::Stage::Modes)
            m_shot_survey = io::read_surveys(m_survey_files, m_solve_file, m_fingerprint, height);
        break;
    case denoise::Stage::Statistics:
        std::tie(m_row_begin, m_row_end) = parse_rows(m_options.rows, height, denoise::kStageBlockRows);
        denoise::check_statistics_rows(m_row_begin, m_row_end, height);
        break;
    case denoise::Stage::Solve:
        m_shot_statistics = io::read_statistics(m_statistics_files, m_fingerprint, height, frames);
        break;
    case denoise::Stage::Write: {
        m_solved = io::read_solve(m_solve_file, m_fingerprint);
        m_shot_survey = io::read_surveys(m_survey_files, m_solve_file, m_fingerprint, height);
        m_bands = io::read_modes(m_modes_bytes, m_solve_file, io::survey_digest(m_shot_survey.sums), m_fingerprint,
                                 reader.width(), height, reader.selected_channel_count());
        // Parsed into the bands: only the names stay, for the JSON.
        for (const io::StageBytes& file : m_modes_bytes)
            m_modes_files.push_back(file.name);
        std::vector<io::StageBytes>().swap(m_modes_bytes);
        break;
    }
    }
}

denoise::Report StageRun::run(denoise::FrameSource& source, denoise::FrameSink& sink,
                              const denoise::Settings& settings, Progress& progress)
{
    const denoise::PassContext context{source, sink, settings, progress};
    switch (m_stage) {
    case denoise::Stage::Statistics: {
        auto result = denoise::statistics_task(context, m_row_begin, m_row_end);
        m_output = io::statistics_bytes(m_fingerprint, result.output);
        return result.report;
    }
    case denoise::Stage::Solve: {
        auto result = denoise::solve_task(context, m_shot_statistics);
        m_output = io::solve_bytes(m_fingerprint, result.output);
        return result.report;
    }
    case denoise::Stage::Survey: {
        auto result = denoise::survey_task(context, m_solved, m_row_begin, m_row_end);
        m_output = io::survey_bytes(m_fingerprint, m_solve_file, result.output);
        return result.report;
    }
    case denoise::Stage::Modes: {
        auto result = denoise::modes_task(context, m_solved, m_shot_survey, m_row_begin, m_row_end);
        m_output = io::modes_bytes(m_fingerprint, m_solve_file, io::survey_digest(m_shot_survey.sums), result.output);
        return result.report;
    }
    default: return denoise::write_task(context, m_solved, m_shot_survey, m_bands);
    }
}

void StageRun::finish(const std::string& output_path) const
{
    if (writes_frames())
        return;
    if (m_options.in_memory)
        m_options.in_memory->output = m_output;
    else
        io::write_text_file(output_path, m_output);
}

nlohmann::ordered_json StageRun::json() const
{
    nlohmann::ordered_json json{{"stage", denoise::stage_name(m_stage)}};
    if (m_stage == denoise::Stage::Statistics || m_stage == denoise::Stage::Survey || m_stage == denoise::Stage::Modes)
        json["rows"] = {m_row_begin, m_row_end - 1};
    if (m_stage == denoise::Stage::Solve)
        for (const io::StageBytes& input : m_statistics_files)
            json["statistics_files"].push_back(input.name);
    if (m_stage != denoise::Stage::Statistics && m_stage != denoise::Stage::Solve)
        json["solve_file"] = m_solve_file.name;
    if (m_stage == denoise::Stage::Modes || m_stage == denoise::Stage::Write)
        for (const io::StageBytes& input : m_survey_files)
            json["survey_files"].push_back(input.name);
    if (m_stage == denoise::Stage::Write)
        for (const std::string& name : m_modes_files)
            json["modes_files"].push_back(name);
    return json;
}

}  // namespace modestack::app
