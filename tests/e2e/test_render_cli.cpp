// End-to-end: `modestack render` writes multi-layer EXRs with the documented
// layers and provenance, deterministically for any --threads, masks work, and
// bad options are refused.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <cmath>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

TEST_CASE("render writes every documented layer, half colour and float geometry, with provenance")
{
    TempDir dir;
    auto result = run_modestack("render --scene switch --frames 30-31 --spp 2 --size 32x24 -q -o " +
                                dir.file("r.####.exr"));
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    CHECK(testkit::list_directory(dir.path()) == std::vector<std::string>{"r.0030.exr", "r.0031.exr"});
    std::vector<std::string> names = testkit::read_channel_names(dir.file("r.0030.exr"));
    for (const char* channel : {"Combined.R", "Combined.A", "DiffDir.G", "DiffInd.B", "DiffCol.R", "Emit.R", "Normal.X",
                                "Depth.Z", "Position.Y", "DiffIndVar.R", "Rendered.V"})
        CHECK_MESSAGE(std::find(names.begin(), names.end(), channel) != names.end(), channel);
    CHECK(testkit::read_string_attribute(dir.file("r.0031.exr"), "modestack:scene") == "switch");
    // Cycles' identity between the passes holds in the written (half) files too.
    auto beauty = testkit::read_channels(dir.file("r.0030.exr"), {"Combined.G"});
    auto albedo = testkit::read_channels(dir.file("r.0030.exr"), {"DiffCol.G"});
    auto direct = testkit::read_channels(dir.file("r.0030.exr"), {"DiffDir.G"});
    auto indirect = testkit::read_channels(dir.file("r.0030.exr"), {"DiffInd.G"});
    auto emission = testkit::read_channels(dir.file("r.0030.exr"), {"Emit.G"});
    for (size_t i = 0; i < beauty.size(); ++i)
        CHECK(std::fabs(beauty[i] - (albedo[i] * (direct[i] + indirect[i]) + emission[i])) <=
              4e-3f * std::max(1.0f, beauty[i]));
}

TEST_CASE("render is byte-identical in its pixels for --threads 1 and 2, and a mask renders only its pixels")
{
    TempDir dir;
    std::string common = "render --scene orbit --frames 3 --spp 3 --size 37x21 -q ";
    REQUIRE(run_modestack(common + "--threads 1 -o " + dir.file("a.####.exr")).exit_code == 0);
    REQUIRE(run_modestack(common + "--threads 2 -o " + dir.file("b.####.exr")).exit_code == 0);
    auto a = testkit::read_native(dir.file("a.0003.exr"));
    CHECK(a == testkit::read_native(dir.file("b.0003.exr")));

    testkit::ExrLayout mask_layout;
    mask_layout.width = 37;
    mask_layout.height = 21;
    mask_layout.channel_names = {"Y"};
    testkit::write_sequence(dir.file("mask.%04d.exr"), {3}, mask_layout,
                            [](int, int x, int y, int) { return x >= 10 && x < 20 && y >= 5 && y < 9 ? 1.0f : 0.0f; });
    REQUIRE(run_modestack(common + "--mask " + dir.file("mask.####.exr") + " -o " + dir.file("m.####.exr")).exit_code == 0);
    auto full = testkit::read_channels(dir.file("a.0003.exr"), {"DiffInd.R", "Combined.G"});
    auto masked = testkit::read_channels(dir.file("m.0003.exr"), {"DiffInd.R", "Combined.G", "Rendered.V"});
    for (int y = 0; y < 21; ++y)
        for (int x = 0; x < 37; ++x) {
            size_t p = static_cast<size_t>(y) * 37 + x;
            bool inside = x >= 10 && x < 20 && y >= 5 && y < 9;
            CHECK(masked[p * 3 + 2] == (inside ? 1.0f : 0.0f));
            CHECK(masked[p * 3 + 0] == (inside ? full[p * 2 + 0] : 0.0f));
            CHECK(masked[p * 3 + 1] == (inside ? full[p * 2 + 1] : 0.0f));
        }
}

TEST_CASE("render: --scene list, and bad options give one line and exit 1 or 2")
{
    auto list = run_modestack("render --scene list");
    CHECK(list.exit_code == 0);
    // One line per scene, starting with its name.
    for (const char* scene : {"static", "orbit", "switch", "spin", "flythrough", "sweep", "cross"})
        CHECK(("\n" + list.out).find("\n" + std::string(scene) + " ") != std::string::npos);
    TempDir dir;
    struct Case {
        std::string arguments;
        int exit_code;
        std::string message;
    };
    std::vector<Case> cases{
        {"--scene nowhere -o " + dir.file("r.####.exr"), 2, "nowhere"},
        {"--scene orbit --spp 0 -o " + dir.file("r.####.exr"), 2, "--spp"},
        {"--scene orbit --size 0x0 -o " + dir.file("r.####.exr"), 2, "--size '0x0'"},
        {"--scene orbit --frames 40-50 -o " + dir.file("r.####.exr"), 2, "frame 49 is outside scene 'orbit' (frames 1-48)"},
        {"--scene orbit", 2, "-o SEQ"},
        {"--scene orbit --frames 1 --size 8x8 -o /proc/version/r.####.exr", 1, "output directory"},
        {"--scene orbit --frames 1 --size 8x8 --mask " + dir.file("none.####.exr") + " -o " + dir.file("r.####.exr"),
         1, "none.0001.exr: frame 1 is missing"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.arguments);
        auto result = run_modestack("render " + c.arguments);
        CHECK(result.exit_code == c.exit_code);
        CHECK(result.err.find('\n') == result.err.size() - 1);
        CHECK_MESSAGE(result.err.find(c.message) != std::string::npos, result.err);
    }
    CHECK(testkit::list_directory(dir.path()).empty());
}
