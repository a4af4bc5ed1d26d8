// The report's browser test (ctest label `browser`): opens a `modestack denoise
// --report` page in headless Chromium over the DevTools protocol and checks what
// a person would: no console errors, the spectrum plot is drawn, moving the rank
// slider changes the displayed image (screenshots before and after, compared
// pixel by pixel), the side-by-side panels zoom together and the exposure control
// changes them. Reports itself skipped (testkit::report_skipped) when Chromium is
// not installed.
//
// browser_check [--report FILE] [--save DIR]: without --report it makes a small
// noisy sequence and its report in a temporary directory; --save keeps the
// screenshots (before.png, after.png, page.png) in DIR.
#include "app/report/image_encoding.h"
#include "io/png_encoding.h"
#include "tests/browser/devtools_pipe.h"
#include "tests/tools/testkit.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <thread>

using namespace modestack;
using nlohmann::json;

namespace {

constexpr int kWidth = 1400, kHeight = 1000;

void check(bool condition, const std::string& what)
{
    if (!condition)
        throw std::runtime_error(what);
    std::printf("ok: %s\n", what.c_str());
}

// A rank-2 shot with noise: a bright gradient, a spot that moves in and out.
std::string make_report(const testkit::TempDir& directory)
{
    testkit::ExrLayout layout;
    layout.width = 96;
    layout.height = 64;
    std::vector<int> frames;
    for (int frame = 1; frame <= 16; ++frame)
        frames.push_back(frame);
    testkit::write_sequence(directory.file("noisy.%04d.exr"), frames, layout, [](int frame, int x, int y, int c) {
        std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
        std::normal_distribution<float> noise(0.0f, 0.08f);
        float base = 0.2f + 0.5f * x / 96.0f + 0.1f * c;
        float spot = std::exp(-((x - 48.0f) * (x - 48.0f) + (y - 32.0f) * (y - 32.0f)) / 120.0f);
        return base + spot * std::sin(0.4f * frame) * std::sin(0.4f * frame) * 2.0f + noise(generator);
    });
    std::string report = directory.file("report.html");
    testkit::CliResult result = testkit::run_modestack(
        fmt::format("denoise {} -o {} --report {} -q", directory.file("noisy.%04d.exr"),
                    directory.file("out/denoised.%04d.exr"), report));
    if (result.exit_code != 0)
        throw std::runtime_error("modestack denoise --report failed: " + result.err);
    return report;
}

io::Image8 screenshot(browser::DevToolsPipe& browser, const std::string& save_as)
{
    json shot = browser.page("Page.captureScreenshot", {{"format", "png"}});
    std::vector<std::uint8_t> bytes = app::report::base64_decode(shot["data"].get<std::string>());
    if (!save_as.empty())
        std::ofstream(save_as, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                        static_cast<std::streamsize>(bytes.size()));
    return io::decode_png(bytes);
}

// Fraction of pixels inside `rect` (viewport CSS pixels = screenshot pixels) that differ.
double changed_fraction(const io::Image8& before, const io::Image8& after, const json& rect)
{
    int x0 = std::max(0, static_cast<int>(std::ceil(rect["x"].get<double>()))),
        y0 = std::max(0, static_cast<int>(std::ceil(rect["y"].get<double>())));
    int x1 = std::min(before.width, static_cast<int>(rect["x"].get<double>() + rect["width"].get<double>())),
        y1 = std::min(before.height, static_cast<int>(rect["y"].get<double>() + rect["height"].get<double>()));
    long changed = 0, total = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            size_t at = (static_cast<size_t>(y) * before.width + x) * before.channels;
            bool differs = false;
            for (int c = 0; c < 3; ++c)
                differs |= std::abs(before.pixels[at + c] - after.pixels[at + c]) > 2;
            changed += differs;
            ++total;
        }
    return total ? static_cast<double>(changed) / total : 0.0;
}

int run(int argc, char** argv)
{
    std::string report, save;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string option = argv[i];
        if (option == "--report")
            report = argv[i + 1];
        else if (option == "--save")
            save = argv[i + 1];
    }
    const std::string chromium = browser::find_chromium();
    if (chromium.empty()) {
        testkit::report_skipped("Chromium is not installed (Debian: apt-get install chromium; or set "
                                "MODESTACK_CHROMIUM); the report was not opened in a browser");
        return 0;
    }
    auto start = std::chrono::steady_clock::now();
    testkit::TempDir directory;
    if (report.empty())
        report = make_report(directory);
    auto saved = [&](const char* name) { return save.empty() ? std::string() : save + "/" + name; };

    browser::DevToolsPipe browser(chromium, kWidth, kHeight);
    browser.page("Page.navigate", {{"url", "file://" + std::filesystem::absolute(report).string()}});
    browser.wait_for_event("Page.loadEventFired", std::chrono::seconds(20));
    json state;
    for (int attempt = 0; attempt < 300; ++attempt) {
        state = browser.evaluate("({ready: window.reportReady === true, error: String(window.reportFailure || '')})");
        if (state["ready"].get<bool>() || !state["error"].get<std::string>().empty())
            break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    check(state["error"].get<std::string>().empty(), "the page's script ran without error " + state.dump());
    check(state["ready"].get<bool>(), "the page decoded and drew every image");

    json spectrum = browser.evaluate(
        "(() => { const paths = [...document.querySelectorAll('#spectrum svg path.series')];"
        " const box = paths.length ? paths[0].getBBox() : {width: 0, height: 0};"
        " return {paths: paths.length, length: paths.length ? paths[0].getTotalLength() : 0,"
        " width: box.width, height: box.height}; })()");
    check(spectrum["paths"].get<int>() >= 1 && spectrum["length"].get<double>() > 10 &&
              spectrum["width"].get<double>() > 10,
          "the spectrum plot is drawn " + spectrum.dump());

    json rect = browser.evaluate(
        "(() => { const canvas = document.getElementById('rank-canvas'); canvas.scrollIntoView({block: 'center'});"
        " const r = canvas.getBoundingClientRect(); return {x: r.x, y: r.y, width: r.width, height: r.height,"
        " value: +document.getElementById('rank-slider').value, max: +document.getElementById('rank-slider').max}; })()");
    check(rect["width"].get<double>() > 100 && rect["max"].get<int>() > rect["value"].get<int>(),
          "the rank slider has modes beyond the chosen N " + rect.dump());
    io::Image8 before = screenshot(browser, saved("before.png"));
    std::string label_before = browser.evaluate("document.getElementById('rank-value').textContent");
    browser.evaluate("(() => { const slider = document.getElementById('rank-slider'); slider.value = slider.max;"
                     " slider.dispatchEvent(new Event('input')); })()");
    io::Image8 after = screenshot(browser, saved("after.png"));
    std::string label_after = browser.evaluate("document.getElementById('rank-value').textContent");
    double fraction = changed_fraction(before, after, rect);
    check(fraction > 0.2, fmt::format("moving the slider changed {:.0f} % of the rank preview's pixels ({} -> {})",
                                      100 * fraction, label_before, label_after));

    json zoom = browser.evaluate(
        "(() => { const viewports = [...document.querySelectorAll('.viewport')];"
        " const r = viewports[0].getBoundingClientRect();"
        " viewports[0].dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: r.x + r.width / 2,"
        " clientY: r.y + r.height / 2, bubbles: true, cancelable: true}));"
        " const transforms = viewports.map(v => v.firstChild.style.transform);"
        " return {count: viewports.length, same: transforms.every(t => t === transforms[0]), transform: transforms[0]}; })()");
    check(zoom["count"].get<int>() >= 3 && zoom["same"].get<bool>() &&
              zoom["transform"].get<std::string>().find("scale(") != std::string::npos,
          "the side-by-side panels zoom together " + zoom.dump());

    json exposure = browser.evaluate(
        "(() => { const canvas = document.querySelector('.viewport canvas');"
        " const sum = () => canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data"
        ".reduce((a, b) => a + b, 0);"
        " const before = sum(); const slider = document.getElementById('exposure');"
        " slider.value = +slider.value + 2; slider.dispatchEvent(new Event('input'));"
        " return {before, after: sum()}; })()");
    check(exposure["after"].get<double>() > exposure["before"].get<double>(),
          "two stops more exposure brighten the panels " + exposure.dump());

    if (!save.empty()) {
        browser.evaluate("(() => { const slider = document.getElementById('exposure'); slider.value = +slider.value - 2;"
                         " slider.dispatchEvent(new Event('input')); window.scrollTo(0, 0); })()");
        json size = browser.evaluate("({height: document.documentElement.scrollHeight})");
        json shot = browser.page("Page.captureScreenshot",
                                 {{"format", "png"},
                                  {"captureBeyondViewport", true},
                                  {"clip", {{"x", 0}, {"y", 0}, {"width", kWidth}, {"height", size["height"]}, {"scale", 1}}}});
        std::vector<std::uint8_t> bytes = app::report::base64_decode(shot["data"].get<std::string>());
        std::ofstream(saved("page.png"), std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    for (const std::string& error : browser.page_errors())
        std::printf("page error: %s\n", error.c_str());
    check(browser.page_errors().empty(), "no console errors, exceptions or failed loads");
    std::printf("browser check passed in %.1f s\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    try {
        return run(argc, argv);
    } catch (const std::exception& error) {
        std::printf("FAILED: %s\n", error.what());
        return 1;
    }
}
