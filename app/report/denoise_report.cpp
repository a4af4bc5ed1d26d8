#include "app/report/denoise_report.h"

#include "app/report/html_report.h"
#include "core/common/error.h"
#include "io/frame_output.h"

#include <fmt/format.h>

#include <filesystem>

namespace modestack::app::report {

CollectorOptions collector_options(int frames)
{
    CollectorOptions options;
    options.shown_indices = choose_shown_frames(frames);
    return options;
}

std::vector<std::vector<double>> scaled_modes(const std::vector<std::vector<double>>& modes,
                                              const std::vector<double>& frame_scales, bool rebuild)
{
    std::vector<std::vector<double>> scaled = modes;
    if (frame_scales.empty())
        return scaled;
    for (std::vector<double>& mode : scaled) {
        if (mode.size() != frame_scales.size())
            throw internal_error("scaled_modes: a frame scale per frame is needed");
        for (size_t t = 0; t < mode.size(); ++t)
            mode[t] = rebuild ? mode[t] * frame_scales[t] : mode[t] / frame_scales[t];
    }
    return scaled;
}

ReportData gather_report(const Collector& collector, const std::vector<EngineRun>& runs,
                         const std::vector<int>& frame_numbers)
{
    ReportData data;
    data.frame_numbers = frame_numbers;
    data.preview_factor = collector.preview_factor();
    data.panel_factor = collector.panel_factor();
    double statistics = 0, survey = 0, solve = 0, rebuild = 0;
    for (const EngineRun& run : runs) {
        const denoise::Report& report = *run.report;
        Segment segment;
        segment.first = run.first;
        segment.count = run.count;
        segment.singular_values = report.singular_values;
        segment.rank_decision = report.rank_decision;
        const std::vector<std::vector<double>>& modes =
            report.preview_temporal_modes.empty() ? report.temporal_modes : report.preview_temporal_modes;
        // The slider rebuilds Σ c_j D_t pt(t, j) from c_j = Σ_t x_t pt(t, j) / D_t, as the engine does.
        segment.coefficient_images =
            collector.coefficient_images(run.first, scaled_modes(modes, report.frame_scales, false));
        segment.temporal_modes = scaled_modes(modes, report.frame_scales, true);
        if (run.first > 0)
            data.cuts.push_back(run.first);
        data.segments.push_back(std::move(segment));
        data.width = report.shape.width;
        data.height = report.shape.height;
        data.channels = report.shape.channels;
        data.non_finite += report.outliers.non_finite;
        data.fireflies += report.outliers.fireflies;
        statistics += report.seconds_statistics;
        survey += report.seconds_filter_survey;
        solve += report.seconds_solve;
        rebuild += report.seconds_rebuild;
    }
    data.seconds = {{"denoise: pass 1 (read, clean, Gram)", statistics},
                    {"denoise: mode filter survey", survey},
                    {"denoise: solve and rank rule", solve},
                    {"denoise: pass 2 (rebuild, sigma, write)", rebuild}};
    data.shown = collector.shown_frames(frame_numbers);
    data.errors.push_back({"estimated (from sigma)", collector.estimated_error()});
    return data;
}

void check_report_path(const std::string& path, const std::vector<std::string>& inputs)
{
    if (path.empty())
        throw usage_error("--report needs a file name (e.g. report.html)");
    std::error_code error;
    if (std::filesystem::is_directory(path, error))
        throw bad_input(path, "--report names a directory: give a file name such as report.html");
    io::check_outputs({path}, inputs);
}

}  // namespace modestack::app::report
