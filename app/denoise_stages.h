// `denoise --stage stats|solve|write` (issue 11): one shot's denoise split into
// farm tasks, one command line each, that pass small files (io/stage_files.h):
//   stats --rows Y0-Y1|I/K -o STATS   the Gram sums of a band of rows;
//   solve --stats STATS... -o SOLVE   every band merged, the temporal modes;
//   survey --solve SOLVE --rows Y0-Y1|I/K -o SURVEY
//                                     the mode filter's SURE sums of a band of rows;
//   modes --solve SOLVE --survey SURVEY... --rows Y0-Y1|I/K -o MODES
//                                     the mode images of a band of rows (and the
//                                     noise and cleaned values sigma needs);
//   write --solve SOLVE --survey SURVEY... --modes MODES... [--frames R|I/K] -o OUT.####.exr
//                                     the outputs of some frames, reading only those.
// The outputs are byte-identical to one `denoise` run with the same options
// (core/denoise/stage_task.h says why).
#pragma once

#include "core/denoise/farm_tasks.h"
#include "io/stage_files.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace modestack::app {

/// The stage files an MPI job (mpi_job.h) hands a task in memory instead of by
/// path; shared between the job and the task, never copied (the modes are large).
struct StageFilesInMemory {
    std::vector<io::StageBytes> stats;    ///< solve input
    std::optional<io::StageBytes> solve;  ///< survey, modes and write input
    std::vector<io::StageBytes> survey;   ///< modes and write input
    std::vector<io::StageBytes> modes;    ///< write input
    std::string output;                   ///< stats, solve, survey or modes output, instead of -o
};

struct StageOptions {
    std::string stage;                ///< "", stats, solve, survey, modes or write
    std::string rows;                 ///< stats, survey, modes: Y0-Y1 (inclusive) or I/K
    std::vector<std::string> stats;   ///< solve: the statistics files
    std::string solve;                ///< survey, modes, write: the solve file
    std::vector<std::string> survey;  ///< modes, write: the survey files
    std::vector<std::string> modes;   ///< write: the modes files
    /// An MPI job's task: its input files' bytes and its output, in memory (null: files).
    std::shared_ptr<StageFilesInMemory> in_memory;
};

void add_stage_options(CLI::App& command, StageOptions& options);

class StageRun {
public:
    /// `command`: the denoise command, whose options as given go into the fingerprint.
    StageRun(const StageOptions& options, const CLI::App& command);

    denoise::Stage stage() const { return m_stage; }
    bool writes_frames() const { return m_stage == denoise::Stage::Write; }
    /// The frames of the shot: `frames_option` (--frames), except for a write task,
    /// whose shot is the solve file's and whose --frames picks the frames it writes.
    std::string shot_frames(const std::string& frames_option) const;
    /// Write task: clears the output paths of the frames it does not write
    /// (--frames RANGE or I/K of `shot`).
    void keep_written_frames(const std::string& frames_option, const std::vector<int>& shot,
                            std::vector<std::string>& paths) const;
    /// Fingerprints the shot, finds the task's rows and reads its input files.
    void prepare(const io::FrameSequence& input, const io::SequenceReader& reader);
    /// Runs the task (core/denoise/farm_tasks.h) and keeps its result for finish().
    denoise::Report run(denoise::FrameSource& source, denoise::FrameSink& sink, const denoise::Settings& settings,
                        Progress& progress);
    /// Stats, solve, survey and modes of an MPI rank: the output goes to memory, not to -o.
    bool output_in_memory() const { return m_options.in_memory != nullptr && !writes_frames(); }
    /// Writes the task's result (not a write task's: its frames are written) to
    /// `output_path`, or to memory for an MPI rank.
    void finish(const std::string& output_path) const;
    /// What the task did, for the JSON summary.
    nlohmann::ordered_json json() const;

private:
    StageOptions m_options;
    const CLI::App& m_command;
    denoise::Stage m_stage;
    int m_row_begin = 0, m_row_end = 0;  ///< stats, survey, modes: the task's rows
    io::ShotFingerprint m_fingerprint;
    std::vector<io::StageBytes> m_statistics_files;  ///< solve: the statistics files
    io::StageBytes m_solve_file;                     ///< survey, modes, write: the solve file
    std::vector<io::StageBytes> m_survey_files;      ///< modes, write: the survey files
    std::vector<io::StageBytes> m_modes_bytes;       ///< write: the modes files, until parsed
    std::vector<std::string> m_modes_files;          ///< write: the modes files' names, for the JSON
    // The typed inputs, read in prepare():
    denoise::Statistics m_shot_statistics;     ///< solve
    denoise::SolvedSums m_solved;              ///< survey, modes, write
    denoise::SurveyRows m_shot_survey;         ///< modes, write
    std::vector<denoise::ModeImages> m_bands;  ///< write
    std::string m_output;                      ///< the result's file bytes, from run()
};

}  // namespace modestack::app
