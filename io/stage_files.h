// The files a farm denoise passes between its tasks (`denoise --stage`, issue 11;
// core/denoise/stage_task.h, farm_tasks.h): one reader and one writer per typed
// result: a statistics task's block sums, the solve task's
// merged sums, a survey task's mode-filter sums and a modes task's images of its rows.
// Each file is one text line naming the format, one line of JSON (the stage,
// the shot's fingerprint, sizes, counts) and the numbers as raw little-endian
// doubles, then floats (a modes file's images), so that every bit survives the
// trip.
//
// The fingerprint says which shot and which method a file belongs to: the input
// frames (numbers, file names without their directory, byte sizes), the shot's
// shape and channels, and every option of the command line that shapes the
// result. Tasks of one job must be given the same options; a file from another
// shot, other options, a missing or a duplicated band is refused with a one-line
// error naming it. The same bytes travel between MPI ranks (mpi_job.h).
#pragma once

#include "core/denoise/stage_task.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace modestack::io {

/// What must agree between the files of one job.
struct ShotFingerprint {
    nlohmann::ordered_json shot;     ///< frames, files, sizes, shape, channels
    nlohmann::ordered_json options;  ///< the method's options as given
};

/// A stage file's bytes and the name its errors give (its path, or the MPI
/// rank that sent it).
struct StageBytes {
    std::string name;
    std::string bytes;
};

/// Reads a stage file whole (errors name `path`).
StageBytes read_stage_bytes(const std::string& path);

/// The frames of the shot a solve file was made for (its fingerprint's
/// "frames"): a write task denoises that shot and writes a part of it.
std::string shot_frames_of_solve_file(const StageBytes& solve);

/// A statistics task's output: its rows' block sums.
std::string statistics_bytes(const ShotFingerprint& fingerprint, const denoise::Statistics& statistics);

/// Checks the statistics files of a job against each other and against
/// `fingerprint`: every block of a shot of `height` rows exactly once. Returns
/// the shot's statistics: every block in row order, the outlier counts summed.
denoise::Statistics read_statistics(const std::vector<StageBytes>& inputs, const ShotFingerprint& fingerprint,
                                    int height, int frames);

/// The solve task's output.
std::string solve_bytes(const ShotFingerprint& fingerprint, const denoise::SolvedSums& solved);

/// Reads a solve file made for `fingerprint`.
denoise::SolvedSums read_solve(const StageBytes& solve, const ShotFingerprint& fingerprint);

/// A survey task's output, tied to the solve file it used.
std::string survey_bytes(const ShotFingerprint& fingerprint, const StageBytes& solve, const denoise::SurveyRows& survey);

/// Checks the survey files of a job: made for `fingerprint` from `solve`, every
/// row of the shot once. Returns every row's sums (none without the mode filter).
denoise::SurveyRows read_surveys(const std::vector<StageBytes>& inputs, const StageBytes& solve,
                                 const ShotFingerprint& fingerprint, int height);

/// Names the survey sums of every row, whatever files held them.
std::string survey_digest(const std::vector<std::vector<double>>& rows);

/// A modes task's output, tied to the solve file and the survey sums
/// (survey_digest) it used.
std::string modes_bytes(const ShotFingerprint& fingerprint, const StageBytes& solve, const std::string& surveys,
                        const denoise::ModeImages& images);

/// Checks the modes files of a job: made for `fingerprint` from `solve` and the
/// surveys of digest `surveys`, every row of the shot once. Returns them in row order.
std::vector<denoise::ModeImages> read_modes(const std::vector<StageBytes>& inputs, const StageBytes& solve,
                                            const std::string& surveys, const ShotFingerprint& fingerprint, int width,
                                            int height, int channels);

}  // namespace modestack::io
