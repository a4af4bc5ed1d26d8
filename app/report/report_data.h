// What the --report HTML page shows, as plain data: gathered by the collector
// around the denoise engine (report_collector.h) and the engine's Report, then
// completed by `modestack run` (refined frames, refine masks, true error) and
// turned into one self-contained HTML file by html_report.h.
#pragma once

#include "core/lowrank/rank_rule.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace modestack::app::report {

/// A scene-linear RGB image, interleaved, y = 0 at the top.
struct LinearImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;  ///< width × height × 3
};

/// One image of the side-by-side row of a shown frame.
struct Panel {
    std::string label; ///< "noisy", "denoised", "refined", "sigma", "refine mask", "estimator map"
    LinearImage image;
    /// Shown as it is, not through the exposure slider: masks and maps, whose
    /// values are codes in [0, 1], not light.
    bool absolute = false;
};

/// A frame shown side by side and in the rank slider.
struct ShownFrame {
    int index = 0;   ///< index in the shot (0-based)
    int number = 0;  ///< frame number as in the file names
    std::vector<Panel> panels;
};

/// One part of the shot as the engine saw it (the whole shot, or a --segments part).
struct Segment {
    int first = 0;  ///< first frame index
    int count = 0;
    std::vector<double> singular_values;
    lowrank::RankDecision rank_decision;
    /// pt(t, j) over the part's frames for j < N_max: [j][t].
    std::vector<std::vector<double>> temporal_modes;
    /// Coefficient images c_j = Σ_t X_small(t) pt(t, j) at preview resolution, j < N_max:
    /// the rebuild of frame t with n modes is Σ_{j<n} c_j pt(t, j).
    std::vector<LinearImage> coefficient_images;
};

/// A curve over the frames of the shot (per-frame error estimate, true error).
struct FrameSeries {
    std::string label;
    std::vector<double> values;  ///< one per frame; NaN where unknown
};

/// Everything the page shows.
struct ReportData {
    std::string title;
    std::string version;
    std::string command;
    std::string input;
    int width = 0;   ///< full resolution of the shot
    int height = 0;
    int channels = 0;  ///< channels denoised (the page shows the first three)
    std::vector<std::string> channel_names;
    std::vector<int> frame_numbers;
    std::vector<Segment> segments;
    std::vector<int> cuts;  ///< frame indices where a new segment starts
    std::vector<ShownFrame> shown;
    int preview_factor = 1;  ///< box size of the rank slider's images (pixels of the shot)
    int panel_factor = 1;    ///< box size of the side-by-side images
    std::vector<FrameSeries> errors;
    std::int64_t non_finite = 0;
    std::int64_t fireflies = 0;
    std::vector<std::pair<std::string, double>> seconds;  ///< timings by stage
    std::vector<std::string> notes;  ///< sentences shown under the title (honest limits)
};

}  // namespace modestack::app::report
