// AOV buffers and their names (see aov.h).
#include "core/render/aov.h"

namespace modestack::render {

void AovImage::reset(int new_width, int new_height, int new_channels)
{
    width = new_width;
    height = new_height;
    channels = new_channels;
    pixels.assign(static_cast<std::size_t>(new_width) * new_height * new_channels, 0.0f);
}

void FrameAovs::reset(int width, int height, bool with_point_lookup)
{
    beauty.reset(width, height, 4);
    diffuse_direct.reset(width, height, 3);
    diffuse_indirect.reset(width, height, 3);
    albedo.reset(width, height, 3);
    emission.reset(width, height, 3);
    normal.reset(width, height, 3);
    depth.reset(width, height, 1);
    position.reset(width, height, 3);
    indirect_variance.reset(width, height, 3);
    rendered.reset(width, height, 1);
    if (with_point_lookup)
        point_lookup.reset(width, height, 2 * kLookupPoints);
    else
        point_lookup = {};
    stats = {};
}

std::vector<AovLayer> aov_layers(const FrameAovs& aovs)
{
    const std::vector<std::string> rgb{"R", "G", "B"}, xyz{"X", "Y", "Z"};
    std::vector<AovLayer> layers{
        {"Combined", {"R", "G", "B", "A"}, &aovs.beauty},
        {"DiffDir", rgb, &aovs.diffuse_direct},
        {"DiffInd", rgb, &aovs.diffuse_indirect},
        {"DiffCol", rgb, &aovs.albedo},
        {"Emit", rgb, &aovs.emission},
        {"Normal", xyz, &aovs.normal},
        {"Depth", {"Z"}, &aovs.depth},
        {"Position", xyz, &aovs.position},
        {"DiffIndVar", rgb, &aovs.indirect_variance},
        {"Rendered", {"V"}, &aovs.rendered},
    };
    if (aovs.point_lookup.channels > 0)
        layers.push_back({"PointLookup", {"I0", "I1", "I2", "I3", "W0", "W1", "W2", "W3"}, &aovs.point_lookup});
    return layers;
}

} // namespace modestack::render
