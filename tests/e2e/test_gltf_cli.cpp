// End-to-end: `modestack render --scene FILE.gltf` renders the committed glTF test
// room (moving camera and object, point light, emissive panel) into EXRs with
// every layer and lit pixels, byte-identically on a second run; reports its
// approximations on stderr; --fps maps frames to time; bad files exit 1.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>

#include <algorithm>

using namespace modestack;
using testkit::run_modestack;
using testkit::TempDir;

namespace {

const std::string kRoom = std::string(MODESTACK_SOURCE_DIR) + "/testdata/gltf/room.gltf";

} // namespace

TEST_CASE("render --scene room.gltf writes lit frames with every layer, deterministically")
{
    TempDir dir;
    std::string common = "render --scene " + kRoom + " --frames 1-2 --spp 2 --size 40x30 -q ";
    auto first = run_modestack(common + "-o " + dir.file("a.####.exr"));
    REQUIRE_MESSAGE(first.exit_code == 0, first.err);
    CHECK(first.err.find("point lights are rendered as emitting spheres") != std::string::npos);
    CHECK(first.err.find("modestack: warning: " + kRoom + ": ") != std::string::npos);
    CHECK(testkit::list_directory(dir.path()) == std::vector<std::string>{"a.0001.exr", "a.0002.exr"});
    std::vector<std::string> names = testkit::read_channel_names(dir.file("a.0001.exr"));
    for (const char* channel : {"Combined.R", "Combined.A", "DiffDir.G", "DiffInd.B", "DiffCol.R", "Emit.R",
                                "Normal.X", "Depth.Z", "Position.Y", "DiffIndVar.R", "Rendered.V"})
        CHECK_MESSAGE(std::find(names.begin(), names.end(), channel) != names.end(), channel);
    CHECK(testkit::read_string_attribute(dir.file("a.0002.exr"), "modestack:scene") == kRoom);
    for (const char* frame : {"a.0001.exr", "a.0002.exr"}) {
        auto beauty = testkit::read_channels(dir.file(frame), {"Combined.G"});
        auto indirect = testkit::read_channels(dir.file(frame), {"DiffInd.G"});
        auto lit = [](const std::vector<float>& v) {
            return std::count_if(v.begin(), v.end(), [](float x) { return x > 0; });
        };
        CHECK(lit(beauty) > static_cast<long>(beauty.size() / 2));
        CHECK(lit(indirect) > 0);
    }
    // The camera moves: frames 1 and 2 differ; a second run is byte-identical.
    CHECK(testkit::read_native(dir.file("a.0001.exr")) != testkit::read_native(dir.file("a.0002.exr")));
    auto second = run_modestack(common + "-o " + dir.file("b.####.exr"));
    REQUIRE_MESSAGE(second.exit_code == 0, second.err);
    for (const char* frame : {"0001", "0002"})
        CHECK(testkit::read_native(dir.file(std::string("a.") + frame + ".exr")) ==
              testkit::read_native(dir.file(std::string("b.") + frame + ".exr")));
}

TEST_CASE("render --scene FILE.gltf: --fps sets the frame range, bad files and options give one line")
{
    TempDir dir;
    auto out = " -o " + dir.file("r.####.exr");
    auto past_end = run_modestack("render --scene " + kRoom + " --frames 25" + out);
    CHECK(past_end.exit_code == 2);
    CHECK(past_end.err.find("frame 25 is outside scene") != std::string::npos);
    auto doubled = run_modestack("render --scene " + kRoom + " --fps 48 --frames 48" + out);
    CHECK(doubled.exit_code == 2);
    CHECK(doubled.err.find("frame 48 is outside scene") != std::string::npos);
    auto builtin = run_modestack("render --scene orbit --fps 30" + out);
    CHECK(builtin.exit_code == 2);
    CHECK(builtin.err.find("--fps applies to glTF scenes") != std::string::npos);
    auto missing = run_modestack("render --scene " + dir.file("nowhere.gltf") + out);
    CHECK(missing.exit_code == 1);
    CHECK(missing.err == "modestack: " + dir.file("nowhere.gltf") +
                             ": cannot read the glTF file (missing, a directory or unreadable)\n");
    CHECK(testkit::list_directory(dir.path()).empty());
}
