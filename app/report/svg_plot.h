// Line plots as inline SVG for the --report page, drawn by our own code (axes,
// ticks, polylines, marker lines, a legend): the page needs a handful of plots,
// no charting framework. Non-finite points (and non-positive ones on a log
// axis) break a line instead of drawing it to infinity.
#pragma once

#include <string>
#include <vector>

namespace modestack::app::report {

/// One polyline.
struct PlotSeries {
    std::string label;
    std::vector<double> x;
    std::vector<double> y;
    std::string color = "#1f77b4";
    bool points = false;  ///< also draw a dot at each point
};

/// A straight line across the plot at x = value (vertical) or y = value (horizontal).
struct PlotMarker {
    double value = 0;
    std::string label;
    std::string color = "#888";
};

/// What to draw.
struct PlotSpec {
    std::string id;  ///< the svg element's id
    std::string title;
    std::string x_label;
    std::string y_label;
    bool log_y = false;
    int width = 640;
    int height = 260;
    std::vector<PlotSeries> series;
    std::vector<PlotMarker> vertical;
    std::vector<PlotMarker> horizontal;
};

/// The plot as an <svg> element (one <path class="series"> per series).
std::string svg_plot(const PlotSpec& spec);

/// `text` with &, <, >, " and ' escaped for HTML and SVG.
std::string escape_html(const std::string& text);

}  // namespace modestack::app::report
