// Glue between `modestack denoise` and the report: the collector's options for
// a shot, the ReportData of a finished run (one engine run, or one per
// --segments part) and the early check of the --report path. The data comes
// back to the caller in DenoiseResult (app/denoise_job.h), so that `modestack
// run` adds the refined frames, refine masks and true error to the same page.
#pragma once

#include "app/report/report_collector.h"
#include "app/report/report_data.h"
#include "core/denoise/engine.h"

#include <string>
#include <vector>

namespace modestack::app::report {

/// Temporal modes the engine reports for the rank slider: N_max = max(2N, this), at most F − 1.
constexpr int kReportModes = 8;

/// What the collector keeps for a shot of `frames` frames.
CollectorOptions collector_options(int frames);

/// One engine run over frames [first, first + count) of the shot.
struct EngineRun {
    int first = 0;
    int count = 0;
    const denoise::Report* report = nullptr;
};

/// The engine's temporal modes [j][t] as the frames are projected on them
/// (`rebuild` false: pt(t, j) / D_t) or rebuilt from them (true: D_t pt(t, j)),
/// D the frame scales the modes were fitted with (denoise::Report::frame_scales,
/// core/denoise/frame_weighting.h; empty: the modes as they are).
std::vector<std::vector<double>> scaled_modes(const std::vector<std::vector<double>>& modes,
                                              const std::vector<double>& frame_scales, bool rebuild);

/// The page's data from the collector and the engine runs (in frame order):
/// spectrum, rank decision and preview modes per run, shown frames, estimated
/// error, counts and the engine's timings. Provenance (title, version, command,
/// input, channel names) is left to the caller.
ReportData gather_report(const Collector& collector, const std::vector<EngineRun>& runs,
                         const std::vector<int>& frame_numbers);

/// Checks before any work that `path` can be written and is not one of `inputs`:
/// Error (bad input or usage) naming it otherwise.
void check_report_path(const std::string& path, const std::vector<std::string>& inputs);

}  // namespace modestack::app::report
