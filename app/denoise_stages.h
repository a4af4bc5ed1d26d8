// `denoise --stage stats|solve|write` (issue 11): one shot's denoise split into
// farm tasks, one command line each, that pass small files (app/stage_files.h):
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

#include "app/stage_files.h"
#include "core/denoise/stage_task.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace modestack::app {

struct StageOptions {
    std::string stage;                ///< "", stats, solve, survey, modes or write
    std::string rows;                 ///< stats, survey, modes: Y0-Y1 (inclusive) or I/K
    std::vector<std::string> stats;   ///< solve: the statistics files
    std::string solve;                ///< survey, modes, write: the solve file
    std::vector<std::string> survey;  ///< modes, write: the survey files
    std::vector<std::string> modes;   ///< write: the modes files
    /// An MPI job (mpi_job.h) passes the files' bytes in memory instead:
    const std::vector<StageBytes>* stats_bytes = nullptr;  ///< solve input, instead of --stats
    const StageBytes* solve_bytes = nullptr;                ///< survey, modes and write input, instead of --solve
    const std::vector<StageBytes>* survey_bytes = nullptr;  ///< modes and write input, instead of --survey
    std::vector<StageBytes>* modes_bytes = nullptr;  ///< write input, instead of --modes (moved from: large)
    std::string* output_bytes = nullptr;                    ///< stats, solve, survey or modes output, instead of -o
};

void add_stage_options(CLI::App& command, StageOptions& options);

class StageRun {
public:
    /// `command`: the denoise command, whose options as given go into the fingerprint.
    StageRun(const StageOptions& options, const CLI::App& command);

    denoise::Stage stage() const { return m_task.stage; }
    bool writes_frames() const { return m_task.stage == denoise::Stage::Write; }
    /// The frames of the shot: `frames_option` (--frames), except for a write task,
    /// whose shot is the solve file's and whose --frames picks the frames it writes.
    std::string shot_frames(const std::string& frames_option) const;
    /// Write task: clears the output paths of the frames it does not write
    /// (--frames RANGE or I/K of `shot`).
    void keep_written_frames(const std::string& frames_option, const std::vector<int>& shot,
                            std::vector<std::string>& paths) const;
    /// Fingerprints the shot and reads the task's input files.
    void prepare(const io::FrameSequence& input, const io::SequenceReader& reader);
    denoise::StageTask& task() { return m_task; }
    /// Stats, solve, survey and modes of an MPI rank: the output goes to output_bytes, not to -o.
    bool output_in_memory() const { return m_options.output_bytes != nullptr; }
    void finish(const std::string& output_path) const;
    /// What the task did, for the JSON summary.
    nlohmann::ordered_json json() const;

private:
    StageOptions m_options;
    const CLI::App& m_command;
    denoise::StageTask m_task;
    ShotFingerprint m_fingerprint;
    std::vector<StageBytes> m_statistics;  ///< solve: the statistics files
    StageBytes m_solve;                    ///< survey, modes, write: the solve file
    std::vector<StageBytes> m_surveys;     ///< modes, write: the survey files
    std::vector<StageBytes> m_modes;       ///< write: the modes files
};

}  // namespace modestack::app
