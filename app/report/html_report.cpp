#include "app/report/html_report.h"

#include "app/report/image_encoding.h"
#include "app/report/report_page.h"
#include "app/report/svg_plot.h"
#include "io/text_output.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace modestack::app::report {
namespace {

using Json = nlohmann::ordered_json;

const char* const kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
constexpr int kPlottedModes = 4;

const char* color(size_t index) { return kColors[index % (sizeof(kColors) / sizeof(kColors[0]))]; }

// The segment holding frame index t.
int segment_of(const ReportData& data, int t)
{
    for (size_t s = 0; s < data.segments.size(); ++s)
        if (t >= data.segments[s].first && t < data.segments[s].first + data.segments[s].count)
            return static_cast<int>(s);
    return 0;
}

std::vector<double> frame_axis(const ReportData& data)
{
    return std::vector<double>(data.frame_numbers.begin(), data.frame_numbers.end());
}

std::vector<PlotMarker> cut_markers(const ReportData& data)
{
    std::vector<PlotMarker> markers;
    for (int cut : data.cuts)
        if (cut >= 0 && cut < static_cast<int>(data.frame_numbers.size()))
            markers.push_back({static_cast<double>(data.frame_numbers[cut]) - 0.5, "cut", "#c00"});
    return markers;
}

std::string spectrum_plot(const ReportData& data)
{
    PlotSpec spec;
    spec.id = "spectrum-plot";
    spec.title = "Singular values (log scale)";
    spec.x_label = "mode j";
    spec.y_label = "singular value";
    spec.log_y = true;
    for (size_t s = 0; s < data.segments.size(); ++s) {
        const Segment& segment = data.segments[s];
        PlotSeries series;
        series.label = data.segments.size() > 1 ? fmt::format("part {}", s + 1) : "σ_j";
        series.color = color(s);
        series.points = true;
        for (size_t j = 0; j < segment.singular_values.size(); ++j) {
            series.x.push_back(static_cast<double>(j + 1));
            series.y.push_back(segment.singular_values[j]);
        }
        spec.series.push_back(series);
        std::string part = data.segments.size() > 1 ? fmt::format(" (part {})", s + 1) : "";
        spec.vertical.push_back({segment.rank_decision.kept_modes + 0.5,
                                 fmt::format("N = {}{}", segment.rank_decision.kept_modes, part), color(s)});
        if (segment.rank_decision.noise_floor > 0)
            spec.horizontal.push_back({segment.rank_decision.noise_floor, "noise floor" + part, "#666"});
    }
    return svg_plot(spec);
}

std::string temporal_plot(const ReportData& data)
{
    PlotSpec spec;
    spec.id = "temporal-plot";
    spec.title = "Temporal weights D_t pt(t, j) of the first modes";
    spec.x_label = "frame";
    spec.y_label = "weight";
    const std::vector<double> frames = frame_axis(data);
    size_t modes = 0;
    for (const Segment& segment : data.segments)
        modes = std::max(modes, std::min<size_t>(kPlottedModes, segment.temporal_modes.size()));
    for (size_t j = 0; j < modes; ++j) {
        PlotSeries series;
        series.label = fmt::format("mode {}", j + 1);
        series.color = color(j);
        // One point per frame; NaN between parts (and where a part has fewer modes) breaks the line.
        for (const Segment& segment : data.segments) {
            for (int t = 0; t < segment.count; ++t) {
                series.x.push_back(frames.at(static_cast<size_t>(segment.first + t)));
                series.y.push_back(j < segment.temporal_modes.size() ? segment.temporal_modes[j][t] : NAN);
            }
            series.x.push_back(NAN);
            series.y.push_back(NAN);
        }
        spec.series.push_back(series);
    }
    spec.vertical = cut_markers(data);
    for (const ShownFrame& frame : data.shown)
        spec.vertical.push_back({static_cast<double>(frame.number), "", "#bbb"});
    return svg_plot(spec);
}

std::string error_plot(const ReportData& data)
{
    PlotSpec spec;
    spec.id = "error-plot";
    spec.title = "Per-frame error (relMSE, log scale)";
    spec.x_label = "frame";
    spec.y_label = "relMSE";
    spec.log_y = true;
    const std::vector<double> frames = frame_axis(data);
    for (size_t k = 0; k < data.errors.size(); ++k)
        spec.series.push_back({data.errors[k].label, frames, data.errors[k].values, color(k), false});
    spec.vertical = cut_markers(data);
    return svg_plot(spec);
}

Json page_data(const ReportData& data)
{
    Json json;
    json["panelWidth"] = 360;
    json["segments"] = Json::array();
    for (const Segment& segment : data.segments) {
        Json entry{
            {"first", segment.first}, {"count", segment.count}, {"rank", segment.rank_decision.kept_modes}};
        Json weights = Json::array();
        for (size_t j = 0; j < segment.coefficient_images.size() && j < segment.temporal_modes.size(); ++j) {
            Json row = Json::array();
            for (double weight : segment.temporal_modes[j])
                row.push_back(std::round(weight * 1e7) / 1e7);
            weights.push_back(row);
        }
        entry["weights"] = weights;
        entry["modes"] = Json::array();
        for (size_t j = 0; j < weights.size(); ++j) {
            QuantizedImage quantized = quantize(segment.coefficient_images[j]);
            entry["modes"].push_back(
                {{"uri", png_data_uri(quantized.image)}, {"offset", quantized.offset}, {"scale", quantized.scale}});
        }
        json["segments"].push_back(entry);
    }
    json["frames"] = Json::array();
    for (const ShownFrame& frame : data.shown) {
        Json panels = Json::array();
        for (const Panel& panel : frame.panels) {
            LogImage encoded = log_encode(panel.image);
            panels.push_back({{"label", panel.label},
                              {"absolute", panel.absolute},
                              {"uri", png_data_uri(encoded.image)},
                              {"low", encoded.low},
                              {"high", encoded.high}});
        }
        json["frames"].push_back(
            {{"index", frame.index}, {"number", frame.number}, {"segment", segment_of(data, frame.index)}, {"panels", panels}});
    }
    return json;
}

std::string resolution_text(int factor)
{
    return factor <= 1 ? "full resolution" : fmt::format("1/{} resolution ({}&times;{} pixel boxes)", factor, factor, factor);
}

std::string number_text(double value) { return std::isfinite(value) ? fmt::format("{:.4g}", value) : "n/a"; }

}  // namespace

std::vector<int> choose_shown_frames(int frames)
{
    std::vector<int> shown;
    for (double at : {0.2, 0.5, 0.8}) {
        int index = std::clamp(static_cast<int>(std::lround(at * (frames - 1))), 0, std::max(0, frames - 1));
        if (frames > 0 && std::find(shown.begin(), shown.end(), index) == shown.end())
            shown.push_back(index);
    }
    return shown;
}

std::string render_html(const ReportData& data)
{
    std::string html;
    html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
    html += fmt::format("<title>{}</title>\n<style>{}</style>\n</head>\n<body>\n", escape_html(data.title), page_style());
    html += fmt::format("<h1>{}</h1>\n", escape_html(data.title));
    html += fmt::format("<p class=\"note\">{} &middot; input <code>{}</code> &middot; {}&times;{} &middot; {} frames "
                        "&middot; channels {}</p>\n",
                        escape_html(data.version), escape_html(data.input), data.width, data.height,
                        data.frame_numbers.size(), escape_html(fmt::format("{}", fmt::join(data.channel_names, ", "))));
    html += fmt::format("<p class=\"note\">command: <code id=\"command\">{}</code></p>\n", escape_html(data.command));
    for (const std::string& note : data.notes)
        html += fmt::format("<p class=\"note\">{}</p>\n", escape_html(note));

    html += "<h2>Rank</h2>\n<div id=\"spectrum\">" + spectrum_plot(data) + "</div>\n";
    for (size_t s = 0; s < data.segments.size(); ++s) {
        const Segment& segment = data.segments[s];
        std::string part = data.segments.size() > 1
                               ? fmt::format("Part {} (frames {}&ndash;{}): ", s + 1, data.frame_numbers.at(segment.first),
                                             data.frame_numbers.at(segment.first + segment.count - 1))
                               : "";
        html += fmt::format("<p class=\"reasoning\">{}N = {} by the <b>{}</b> rule. {}</p>\n", part,
                            segment.rank_decision.kept_modes, escape_html(segment.rank_decision.rule),
                            escape_html(segment.rank_decision.reasoning));
    }
    html += "<h2>Temporal weights</h2>\n<div id=\"temporal\">" + temporal_plot(data) + "</div>\n";
    if (!data.cuts.empty())
        html += "<p class=\"note\">Red dashed lines: segment cuts (each part has its own modes).</p>\n";
    html +=
        "<h2>Spatial modes</h2>\n<p class=\"note\">Coefficient images c_j = &Sigma;_t X(t) pt(t, j) / D_t of "
        "the downsampled noisy frames, D_t each frame's measured noise scale (1 with --frame-noise even; "
        "each image scaled to its own range; grey = 0 only by chance).</p>\n"
        "<div id=\"modes\" class=\"row modes\"></div>\n";

    html += "<h2>Rank slider</h2>\n";
    html += fmt::format(
        "<p class=\"note\">The rebuild &Sigma;<sub>j&lt;n</sub> c<sub>j</sub> D<sub>t</sub> pt(t, j) "
        "computed in the "
        "page at {} from the unfiltered modes (no mode filter, no firefly clamp, 8-bit "
        "quantized coefficient images): a preview of what N changes, not the denoised output.</p>\n",
        resolution_text(data.preview_factor));
    html += "<div class=\"controls\"><select id=\"rank-frame\"></select> <input id=\"rank-slider\" type=\"range\" "
            "min=\"1\" max=\"1\" step=\"1\" value=\"1\"> <span id=\"rank-value\"></span></div>\n"
            "<canvas id=\"rank-canvas\" width=\"1\" height=\"1\"></canvas>\n";

    html += "<h2>Frames side by side</h2>\n";
    html += fmt::format("<p class=\"note\">At {}, log-encoded in 8 bits (16 stops, about "
                        "2 % steps) and tonemapped here: linear &times; 2<sup>exposure</sup>, clipped, sRGB. Wheel to "
                        "zoom, drag to pan; all panels follow.</p>\n",
                        resolution_text(data.panel_factor));
    html += "<div class=\"controls\">exposure <input id=\"exposure\" type=\"range\" step=\"0.5\"> <span "
            "id=\"exposure-value\"></span> &nbsp; zoom <button id=\"zoom-half\">&minus;</button><button "
            "id=\"zoom-2\">+</button><button id=\"zoom-fit\">fit</button> <span id=\"zoom-value\"></span></div>\n"
            "<div id=\"frames\"></div>\n";

    html += "<h2>Error over the shot</h2>\n<div id=\"errors\">" + error_plot(data) + "</div>\n";
    html += "<p class=\"note\">Estimated: mean of &sigma;&sup2; / (value&sup2; + 0.01) over the shown channels, from "
            "the sigma the denoiser writes. True: relMSE against the reference, when there is one.</p>\n";

    html += "<h2>Counts and timings</h2>\n<table id=\"counts\">\n";
    html += fmt::format("<tr><th>NaN/Inf values replaced</th><td>{}</td></tr>\n", data.non_finite);
    html += fmt::format("<tr><th>fireflies clamped</th><td>{}</td></tr>\n", data.fireflies);
    for (const auto& [stage, seconds] : data.seconds)
        html += fmt::format("<tr><th>{} (s)</th><td>{}</td></tr>\n", escape_html(stage), number_text(seconds));
    html += "</table>\n";

    // "</" cannot appear inside a script element: JSON allows "<\/" for it.
    std::string json = page_data(data).dump();
    for (size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at + 3))
        json.replace(at, 2, "<\\/");
    html += "<script type=\"application/json\" id=\"report-data\">" + json + "</script>\n";
    html += fmt::format("<script>{}</script>\n</body>\n</html>\n", page_script());
    return html;
}

void write_report(const std::string& path, const ReportData& data)
{
    io::write_text_file(path, render_html(data));
}

}  // namespace modestack::app::report
