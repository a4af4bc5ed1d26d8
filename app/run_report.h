// `modestack run --report`: the denoise stage writes its report page (app/report/);
// run completes it with what only run knows (refined frames, refine masks, the
// true error against a reference, every stage's time) and writes it again.
#pragma once

#include "app/report/report_data.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace modestack::app {

/// Adds run's panels, errors and stage times to the denoise stage's `data`.
/// `errors[0][version][frame]` is the indirect layer's true relMSE (empty without a
/// reference); `seconds` run's stage times.
void complete_report(report::ReportData& data, const std::string& scene_name, const io::SequenceReader& refined,
                     const io::FrameSequence& masks, const std::vector<std::vector<std::vector<double>>>& errors,
                     const nlohmann::ordered_json& seconds);

}  // namespace modestack::app
