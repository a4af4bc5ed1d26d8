// The report page: self-contained (no network references, images only as data:
// URIs, no "</" inside its data block), its plots drawn from the data (log axis,
// breaks at NaN), and the frames it shows.
#include "app/report/html_report.h"
#include "app/report/svg_plot.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <regex>

using namespace modestack::app::report;

namespace {

LinearImage ramp(int width, int height, float scale)
{
    LinearImage image{width, height, {}};
    for (int i = 0; i < width * height * 3; ++i)
        image.rgb.push_back(scale * static_cast<float>(i % 17) / 17.0f);
    return image;
}

ReportData sample_data()
{
    ReportData data;
    data.title = "shot </script><b>";
    data.version = "modestack 0.1.0";
    data.command = "modestack denoise in.####.exr -o out.####.exr --report https://example.com/r.html";
    data.width = 16;
    data.height = 8;
    data.frame_numbers = {1, 2, 3, 4, 5, 6};
    Segment segment;
    segment.first = 0;
    segment.count = 6;
    segment.singular_values = {10, 3, 0.5, 0.4, 0.3};
    segment.rank_decision.kept_modes = 2;
    segment.rank_decision.rule = "press";
    segment.rank_decision.reasoning = "PRESS is lowest at N = 2.";
    segment.rank_decision.noise_floor = 0.6;
    for (int j = 0; j < 4; ++j) {
        segment.temporal_modes.push_back({0.1 * j, 0.2, 0.3, 0.4, 0.5, 0.6});
        segment.coefficient_images.push_back(ramp(8, 4, 1.0f + j));
    }
    data.segments.push_back(segment);
    ShownFrame frame;
    frame.index = 2;
    frame.number = 3;
    frame.panels = {{"noisy", ramp(8, 4, 2)}, {"denoised", ramp(8, 4, 2)}, {"sigma", ramp(8, 4, 0.1f)}};
    data.shown.push_back(frame);
    data.errors.push_back({"estimated", {0.1, 0.2, NAN, 0.05, 0.1, 0.1}});
    data.seconds = {{"denoise: total", 1.5}};
    return data;
}

std::string data_block(const std::string& html)
{
    const std::string open = "<script type=\"application/json\" id=\"report-data\">";
    size_t begin = html.find(open) + open.size();
    return html.substr(begin, html.find("</script>", begin) - begin);
}

}  // namespace

TEST_CASE("the report page is self-contained: no network references, images as data URIs")
{
    ReportData data = sample_data();
    std::string html = render_html(data);
    // The only URL is the one typed in the command line, shown as escaped text.
    std::regex network(R"((src|href)\s*=\s*["']?\s*(https?:)?//|url\(\s*["']?(https?:)?//|@import)");
    CHECK_FALSE(std::regex_search(html, network));
    CHECK(html.find("https://") == html.find("https://example.com/r.html"));
    CHECK(html.find("https://", html.find("https://") + 1) == std::string::npos);
    CHECK(html.find("shot </script>") == std::string::npos);  // the title is escaped
    CHECK(html.find("shot &lt;/script&gt;&lt;b&gt;") != std::string::npos);
    nlohmann::json page = nlohmann::json::parse(data_block(html));
    REQUIRE(page["segments"].size() == 1);
    CHECK(page["segments"][0]["rank"] == 2);
    CHECK(page["segments"][0]["modes"].size() == 4);
    CHECK(page["segments"][0]["weights"].size() == 4);
    for (const auto& mode : page["segments"][0]["modes"])
        CHECK(mode["uri"].get<std::string>().rfind("data:image/png;base64,", 0) == 0);
    REQUIRE(page["frames"].size() == 1);
    CHECK(page["frames"][0]["number"] == 3);
    CHECK(page["frames"][0]["panels"].size() == 3);
    CHECK(data_block(html).find("</") == std::string::npos);
    CHECK(html.find("PRESS is lowest at N = 2.") != std::string::npos);
    CHECK(html.find("id=\"spectrum-plot\"") != std::string::npos);
    CHECK(html.find("id=\"temporal-plot\"") != std::string::npos);
    CHECK(html.find("id=\"error-plot\"") != std::string::npos);
}

TEST_CASE("plots break lines at NaN and drop non-positive values on a log axis")
{
    PlotSpec spec;
    spec.log_y = true;
    spec.series.push_back({"s", {1, 2, 3, 4, 5, 6}, {1, 10, -1, 100, NAN, 1000}});
    spec.horizontal.push_back({5, "floor"});
    spec.vertical.push_back({2.5, "N = 2"});
    std::string svg = svg_plot(spec);
    std::smatch path;
    REQUIRE(std::regex_search(svg, path, std::regex(R"re(class="series" d="([^"]*)")re")));
    std::string d = path[1];
    CHECK(std::count(d.begin(), d.end(), 'M') == 3);  // 1–10, 100, 1000
    CHECK(std::count(d.begin(), d.end(), 'L') == 1);
    CHECK(std::count(svg.begin(), svg.end(), '\n') > 5);
    CHECK(svg.find("class=\"marker\"") != std::string::npos);
    CHECK(svg.find(">100<") != std::string::npos);  // decade ticks
}

TEST_CASE("three shown frames spread over the shot, fewer for short shots")
{
    CHECK(choose_shown_frames(100) == std::vector<int>{20, 50, 79});
    CHECK(choose_shown_frames(3) == std::vector<int>{0, 1, 2});
    CHECK(choose_shown_frames(1) == std::vector<int>{0});
    CHECK(choose_shown_frames(0).empty());
}
