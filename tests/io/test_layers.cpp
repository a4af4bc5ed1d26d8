// --layer selection for Cycles, Arnold and RenderMan channel naming.
#include "core/common/error.h"
#include "io/layers.h"

#include <doctest/doctest.h>

using namespace modestack;

TEST_CASE("layers: Cycles ViewLayer.DiffInd.* is found by --layer DiffInd")
{
    std::vector<std::string> channels{"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                                      "ViewLayer.Combined.A", "ViewLayer.DiffInd.R",  "ViewLayer.DiffInd.G",
                                      "ViewLayer.DiffInd.B",  "ViewLayer.Depth.Z"};
    auto selected = io::select_layers(channels, {"DiffInd"}, "f.exr");
    REQUIRE(selected.size() == 1);
    CHECK(selected[0].name == "ViewLayer.DiffInd");
    CHECK(selected[0].channel_indices == std::vector<int>{4, 5, 6});
    CHECK(selected[0].sigma_names == std::vector<std::string>{"ViewLayer.DiffInd.sigma.R", "ViewLayer.DiffInd.sigma.G",
                                                              "ViewLayer.DiffInd.sigma.B"});
    // The full name works too; alpha of Combined is never denoised.
    auto combined = io::select_layers(channels, {"ViewLayer.Combined"}, "f.exr");
    CHECK(combined[0].channel_indices == std::vector<int>{0, 1, 2});
}

TEST_CASE("layers: Arnold diffuse_indirect.* and RenderMan indirectdiffuse.*")
{
    std::vector<std::string> arnold{"R", "G", "B", "A", "diffuse_indirect.R", "diffuse_indirect.G", "diffuse_indirect.B"};
    CHECK(io::select_layers(arnold, {"diffuse_indirect"}, "f.exr")[0].channel_indices == std::vector<int>{4, 5, 6});
    std::vector<std::string> renderman{"indirectdiffuse.R", "indirectdiffuse.G", "indirectdiffuse.B", "z.Z"};
    auto selected = io::select_layers(renderman, {"indirectdiffuse"}, "f.exr");
    CHECK(selected[0].channel_names[2] == "indirectdiffuse.B");
    // A name must match whole components: "diffuse" does not find "indirectdiffuse".
    CHECK_THROWS_AS(io::select_layers(renderman, {"diffuse"}, "f.exr"), Error);
}

TEST_CASE("layers: a bare channel such as Arnold's depth Z is a layer of one channel, R, G, B and A are not")
{
    std::vector<std::string> arnold{
        "A", "B", "G", "R", "Z", "diffuse_albedo.B", "diffuse_albedo.G", "diffuse_albedo.R"};
    auto depth = io::select_layers(arnold, {"Z"}, "f.exr");
    REQUIRE(depth.size() == 1);
    CHECK(depth[0].name == "Z");
    CHECK(depth[0].channel_indices == std::vector<int>{4});
    CHECK(depth[0].channel_names == std::vector<std::string>{"Z"});
    CHECK_THROWS_AS(io::select_layers(arnold, {"R"}, "f.exr"), Error);
    CHECK_THROWS_AS(io::select_layers(arnold, {"depth"}, "f.exr"), Error);
    // A layer of that name wins over the bare channel.
    std::vector<std::string> both{"Z", "Z.X"};
    CHECK(io::select_layers(both, {"Z"}, "f.exr")[0].channel_names == std::vector<std::string>{"Z.X"});
}

TEST_CASE("layers: without --layer the only RGB set is used, otherwise the error lists the layers")
{
    CHECK(io::select_layers({"R", "G", "B", "A", "Z"}, {}, "f.exr")[0].channel_indices == std::vector<int>{0, 1, 2});
    try {
        io::select_layers({"a.R", "a.G", "a.B", "b.R", "b.G", "b.B"}, {}, "shot.0001.exr");
        FAIL("no error");
    } catch (const Error& error) {
        std::string message = error.what();
        CHECK(message.find("shot.0001.exr") == 0);
        CHECK(message.find("a [R,G,B]") != std::string::npos);
        CHECK(message.find("b [R,G,B]") != std::string::npos);
    }
}

TEST_CASE("layers: a selector matching two view layers is ambiguous and unknown names list what exists")
{
    std::vector<std::string> channels{"left.DiffInd.R", "left.DiffInd.G", "left.DiffInd.B",
                                      "right.DiffInd.R", "right.DiffInd.G", "right.DiffInd.B"};
    CHECK_THROWS_WITH_AS(io::select_layers(channels, {"DiffInd"}, "f.exr"),
                         doctest::Contains("ambiguous"), Error);
    CHECK(io::select_layers(channels, {"right.DiffInd"}, "f.exr")[0].channel_indices == std::vector<int>{3, 4, 5});
    CHECK_THROWS_WITH_AS(io::select_layers(channels, {"GlossInd"}, "f.exr"), doctest::Contains("left.DiffInd [R,G,B]"),
                         Error);
}

TEST_CASE("layers: a multi-part file's part of bare channels names their layer, others keep theirs")
{
    using V = std::vector<std::string>;
    // Arnold/Karma/Nuke: a part per AOV, channels bare; sigma added by denoise reads back under the layer
    // too.
    CHECK(io::part_channel_names("diffuse_indirect", {"R", "G", "B", "sigma.R"}) ==
          V{"diffuse_indirect.R", "diffuse_indirect.G", "diffuse_indirect.B", "diffuse_indirect.sigma.R"});
    // Channels that all carry a layer stay as they are, whatever the part's name.
    CHECK(io::part_channel_names("aux", {"Normal.X", "ViewLayer.Depth.Z"}) ==
          V{"Normal.X", "ViewLayer.Depth.Z"});
    // A part without a name (a single-part file) keeps bare names.
    CHECK(io::part_channel_names("", {"R", "G", "B"}) == V{"R", "G", "B"});
    // --layer finds the part's layer.
    const V names = io::part_channel_names("diffuse_indirect", {"R", "G", "B"});
    CHECK(io::select_layers(names, {"diffuse_indirect"}, "f.exr").front().channel_names == names);
}
