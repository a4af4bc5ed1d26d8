// The --report page: one self-contained HTML file (no network: styles, script,
// plots and images are all inside it, the images as PNG data: URIs) built from
// ReportData. Plots are inline SVG (svg_plot.h); the images are encoded by
// image_encoding.h and drawn by the page's script (report_page.h).
#pragma once

#include "app/report/report_data.h"

#include <string>
#include <vector>

namespace modestack::app::report {

/// Frame indices a report shows side by side and in the rank slider: three
/// spread over the shot (at about 20 %, 50 % and 80 %), fewer for short shots.
std::vector<int> choose_shown_frames(int frames);

/// The page.
std::string render_html(const ReportData& data);

/// Writes the page to `path` atomically (a temporary name, renamed when
/// complete). Throws Error (bad input) naming `path` when it cannot be written.
void write_report(const std::string& path, const ReportData& data);

}  // namespace modestack::app::report
