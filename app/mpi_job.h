// `mpirun -n K modestack denoise ...` (issue 11): the farm stages of
// denoise_stages.h run by K ranks of one MPI job, their files passed as bytes
// over MPI instead of shared storage. Rank r computes the statistics of share
// r + 1 of K of the rows; rank 0 gathers them in rank order (= row order, so
// the merge is the one a single run does), solves and broadcasts the solve
// file; rank r runs the mode filter's survey and then computes the mode images
// of share r + 1 of K of the rows, every rank gathering all ranks' results (the
// N spatial modes shared), and rank r then writes share r + 1 of K of the
// frames, reading only those. The outputs are
// the bits of one run. A rank that fails prints its error and aborts the job
// (MPI_Abort) with its exit code, so that no rank waits for it forever.
#pragma once

#include "app/denoise_stages.h"

#include <functional>

namespace modestack::app {

/// True in a process that mpirun started as one of K > 1 ranks (Open MPI sets
/// OMPI_COMM_WORLD_SIZE, other launchers PMI_SIZE).
bool started_by_mpirun();

/// One stage of the job: `stage` (its stage, rows and StageFilesInMemory: the
/// input files it is handed, and where it leaves its output), `frames` the
/// --frames to use, `lead` whether this rank reports (progress, summary line,
/// --json). Returns the exit code.
using RunStage = std::function<int(const StageOptions& stage, const std::string& frames, bool lead)>;

/// Runs the job's five stages on this rank; `frames` is the command's --frames.
int run_mpi_denoise(const std::string& frames, const RunStage& run_stage);

}  // namespace modestack::app
