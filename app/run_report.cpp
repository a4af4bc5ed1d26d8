#include "app/run_report.h"

#include "app/command.h"
#include "app/report/report_collector.h"
#include "app/run_composite.h"
#include "io/mask_image.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::app {
namespace {

// A frame of `reader` box-downsampled like the report's other panels.
report::LinearImage report_panel(const std::vector<float>& values, int width, int height, int channels,
                                 int factor)
{
    report::BoxImage box(width, height, channels, factor);
    for (int y = 0; y < height; ++y)
        box.add_row(y, values.data() + static_cast<std::size_t>(y) * width * channels);
    return box.mean();
}

}  // namespace

// The denoise stage's report page completed with what only `run` knows: the
// refined frames and refine masks of the shown frames, the true error when there
// is a reference, every stage's time and run's own command line.
void complete_report(report::ReportData& data, const std::string& scene_name, const io::SequenceReader& refined,
                     const io::FrameSequence& masks, const std::vector<std::vector<std::vector<double>>>& errors,
                     const nlohmann::ordered_json& seconds)
{
    data.title = fmt::format("modestack run: scene {}", scene_name);
    data.command = command_line();
    for (report::ShownFrame& frame : data.shown) {
        const int width = refined.width(), height = refined.height();
        std::vector<float> refined_rgb = read_frame(refined, frame.index);
        std::vector<std::uint8_t> mask = io::read_mask(masks.files.at(frame.index), width, height);
        std::vector<float> mask_values(mask.begin(), mask.end());
        auto at = frame.panels.begin() + std::min<std::ptrdiff_t>(2, static_cast<std::ptrdiff_t>(frame.panels.size()));
        frame.panels.insert(at, {"refined", report_panel(refined_rgb, width, height, 3, data.panel_factor)});
        frame.panels.push_back(
            {"refine mask", report_panel(mask_values, width, height, 1, data.panel_factor), true});
    }
    if (!errors[0][0].empty()) {
        data.errors.push_back({"true (against the reference): denoised", errors[0][1]});
        data.errors.push_back({"true (against the reference): refined", errors[0][2]});
    }
    data.notes.push_back(
        "Denoised: the DiffInd layer (run denoises DiffDir too, on its own modes, before it); "
        "refined: DiffInd after re-rendering the unsure pixels.");
    data.seconds.clear();
    for (const char* stage : {"render", "denoise", "refine", "composite", "reference"})
        if (seconds.contains(stage))
            data.seconds.push_back({fmt::format("run: {}", stage), seconds[stage].get<double>()});
}


}  // namespace modestack::app
