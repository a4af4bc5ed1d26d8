#include "app/report/svg_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace modestack::app::report {
namespace {

constexpr double kLeft = 62, kRight = 12, kTop = 26, kBottom = 40;

struct Range {
    double low = std::numeric_limits<double>::infinity();
    double high = -std::numeric_limits<double>::infinity();
    void add(double value)
    {
        low = std::min(low, value);
        high = std::max(high, value);
    }
    bool empty() const { return !(low <= high); }
};

bool usable(double value, bool log) { return std::isfinite(value) && (!log || value > 0); }

// "Nice" linear ticks: steps of 1, 2 or 5 × 10^k, about five of them.
std::vector<double> linear_ticks(double low, double high)
{
    double span = high - low, raw = span / 5, magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    double step = raw / magnitude < 1.5 ? magnitude : raw / magnitude < 3.5 ? 2 * magnitude : 5 * magnitude;
    std::vector<double> ticks;
    for (double tick = std::ceil(low / step) * step; tick <= high + step * 1e-9; tick += step)
        ticks.push_back(std::abs(tick) < step * 1e-9 ? 0.0 : tick);
    return ticks;
}

std::string tick_text(double value)
{
    return std::abs(value) >= 1e4 || (value != 0 && std::abs(value) < 1e-3) ? fmt::format("{:.0e}", value)
                                                                            : fmt::format("{:g}", value);
}

}  // namespace

std::string escape_html(const std::string& text)
{
    std::string escaped;
    for (char character : text) {
        switch (character) {
        case '&': escaped += "&amp;"; break;
        case '<': escaped += "&lt;"; break;
        case '>': escaped += "&gt;"; break;
        case '"': escaped += "&quot;"; break;
        case '\'': escaped += "&#39;"; break;
        default: escaped += character;
        }
    }
    return escaped;
}

std::string svg_plot(const PlotSpec& spec)
{
    Range x_range, y_range;
    for (const PlotSeries& series : spec.series)
        for (size_t i = 0; i < std::min(series.x.size(), series.y.size()); ++i)
            if (std::isfinite(series.x[i]) && usable(series.y[i], spec.log_y)) {
                x_range.add(series.x[i]);
                y_range.add(spec.log_y ? std::log10(series.y[i]) : series.y[i]);
            }
    for (const PlotMarker& marker : spec.horizontal)
        if (usable(marker.value, spec.log_y))
            y_range.add(spec.log_y ? std::log10(marker.value) : marker.value);
    if (x_range.empty())
        x_range = {0, 1};
    if (y_range.empty())
        y_range = {0, 1};
    if (x_range.high == x_range.low)
        x_range = {x_range.low - 0.5, x_range.high + 0.5};
    if (y_range.high == y_range.low)
        y_range = {y_range.low - 0.5, y_range.high + 0.5};
    if (spec.log_y)
        y_range = {std::floor(y_range.low), std::ceil(y_range.high)};
    else {
        double pad = 0.05 * (y_range.high - y_range.low);
        y_range = {y_range.low - pad, y_range.high + pad};
    }
    const double plot_width = spec.width - kLeft - kRight, plot_height = spec.height - kTop - kBottom;
    auto to_x = [&](double x) { return kLeft + (x - x_range.low) / (x_range.high - x_range.low) * plot_width; };
    auto to_y = [&](double y) {
        double value = spec.log_y ? std::log10(y) : y;
        return kTop + (1 - (value - y_range.low) / (y_range.high - y_range.low)) * plot_height;
    };

    std::string svg = fmt::format(
        "<svg id=\"{}\" class=\"plot\" width=\"{}\" height=\"{}\" "
        "viewBox=\"0 0 {} {}\" font-family=\"sans-serif\" font-size=\"11\">\n",
        escape_html(spec.id), spec.width, spec.height, spec.width, spec.height);
    svg += fmt::format("<text x=\"{}\" y=\"16\" font-size=\"13\" font-weight=\"bold\">{}</text>\n", kLeft,
                       escape_html(spec.title));
    svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#999\"/>\n", kLeft,
                       kTop, plot_width, plot_height);
    // Ticks and grid.
    std::vector<double> y_ticks;
    if (spec.log_y) {
        int decades = static_cast<int>(y_range.high - y_range.low);
        int step = std::max(1, decades / 6);
        for (int k = static_cast<int>(y_range.low); k <= static_cast<int>(y_range.high); k += step)
            y_ticks.push_back(std::pow(10.0, k));
    } else {
        y_ticks = linear_ticks(y_range.low, y_range.high);
    }
    for (double tick : y_ticks) {
        double y = to_y(tick);
        svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>"
                           "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n",
                           kLeft, y, kLeft + plot_width, y, kLeft - 4, y + 4, tick_text(tick));
    }
    for (double tick : linear_ticks(x_range.low, x_range.high)) {
        double x = to_x(tick);
        svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>"
                           "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
                           x, kTop, x, kTop + plot_height, x, kTop + plot_height + 14, tick_text(tick));
    }
    svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", kLeft + plot_width / 2,
                       spec.height - 6, escape_html(spec.x_label));
    svg += fmt::format("<text transform=\"translate(12 {:.1f}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                       kTop + plot_height / 2, escape_html(spec.y_label));
    // Markers.
    for (const PlotMarker& marker : spec.vertical) {
        if (!std::isfinite(marker.value))
            continue;
        double x = to_x(marker.value);
        svg += fmt::format("<line class=\"marker\" x1=\"{:.1f}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{}\" stroke=\"{}\" "
                           "stroke-dasharray=\"4 3\"/><text x=\"{:.1f}\" y=\"{}\" fill=\"{}\">{}</text>\n",
                           x, kTop, x, kTop + plot_height, marker.color, x + 3, kTop + 11, marker.color,
                           escape_html(marker.label));
    }
    for (const PlotMarker& marker : spec.horizontal) {
        if (!usable(marker.value, spec.log_y))
            continue;
        double y = to_y(marker.value);
        svg += fmt::format("<line class=\"marker\" x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"{}\" "
                           "stroke-dasharray=\"6 3\"/><text x=\"{}\" y=\"{:.1f}\" fill=\"{}\" "
                           "text-anchor=\"end\">{}</text>\n",
                           kLeft, y, kLeft + plot_width, y, marker.color, kLeft + plot_width - 3, y - 3,
                           marker.color, escape_html(marker.label));
    }
    // Series and legend.
    double legend_y = kTop + 14;
    for (const PlotSeries& series : spec.series) {
        std::string path, dots;
        bool pen_down = false;
        for (size_t i = 0; i < std::min(series.x.size(), series.y.size()); ++i) {
            if (!std::isfinite(series.x[i]) || !usable(series.y[i], spec.log_y)) {
                pen_down = false;
                continue;
            }
            double x = to_x(series.x[i]), y = to_y(series.y[i]);
            path += fmt::format("{}{:.1f} {:.1f} ", pen_down ? "L" : "M", x, y);
            pen_down = true;
            if (series.points)
                dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.2\" fill=\"{}\"/>", x, y, series.color);
        }
        if (!path.empty())
            path.pop_back();
        svg += fmt::format("<path class=\"series\" d=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\"/>{}\n",
                           path, series.color, dots);
        if (!series.label.empty()) {
            double x = kLeft + plot_width - 150;
            svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" "
                               "stroke-width=\"2\"/><text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n",
                               x, legend_y - 4, x + 18, legend_y - 4, series.color, x + 22, legend_y,
                               escape_html(series.label));
            legend_y += 14;
        }
    }
    svg += "</svg>\n";
    return svg;
}

}  // namespace modestack::app::report
