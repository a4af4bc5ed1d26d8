// The image buffers one rendered frame produces (its AOVs: arbitrary output
// variables) and the channel names we suggest for them, following Cycles so that
// compositing scripts and the denoiser's --layer option find them under the names
// artists know. Every buffer is float, channels interleaved, rows top to bottom
// (y = 0 is the top row), x left to right.
//
// Lighting layers follow Cycles' convention: DiffDir and DiffInd are light
// arriving at the first surface, NOT multiplied by its albedo (Cycles divides the
// "colour-weighted" light by DiffCol). So for the Lambertian scenes of modestack
//     Combined.RGB = DiffCol × (DiffDir + DiffInd) + Emit
// holds per pixel up to float rounding: the tracer accumulates albedo-weighted
// light over the pixel's samples and divides by the accumulated albedo at the end.
// Where DiffCol is 0 the lighting layers are 0.
//
// Suggested EXR channel names (prefix with a view-layer name if wanted):
//   Combined.{R,G,B,A}   beauty; A = fraction of samples that hit a surface
//   DiffDir.{R,G,B}      diffuse direct light (one bounce), not multiplied by albedo
//   DiffInd.{R,G,B}      diffuse indirect light (two or more bounces), not × albedo
//   DiffCol.{R,G,B}      albedo of the first surface hit
//   Emit.{R,G,B}         radiance emitted by the first surface hit
//   Normal.{X,Y,Z}       world-space unit normal of the first hit, facing the camera
//   Depth.Z              planar camera depth (distance along the view axis), metres
//   Position.{X,Y,Z}     world-space position of the first hit, metres
//   DiffIndVar.{R,G,B}   variance of the DiffInd pixel value (the sample variance of
//                        the per-sample estimates divided by spp): the squared noise
//                        level a denoiser can use; 0 at 1 spp (unknown)
//   Rendered.V           1 where the pixel was rendered, 0 where a mask left it out
//   PointLookup.{I0..I3,W0..W3}  only when rendering for object space: the ids of
//                        the (up to) four surface points (surface_points.h) whose
//                        weighted sum Σ Wk·value(Ik) gives the pixel's DiffInd, the
//                        weights summing to 1 (0 where no sample saw any albedo);
//                        unused slots have I = −1, W = 0. Ids are exact in float
//                        (fewer than 2^24 points).
// All layers are box-filtered averages over the pixel's samples.
#pragma once

#include <string>
#include <vector>

namespace modestack::render {

/// One AOV: width × height pixels of `channels` interleaved floats.
struct AovImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels; ///< size width·height·channels, row-major, y = 0 at the top

    /// Sets the size and fills with zeros.
    void reset(int new_width, int new_height, int new_channels);
    /// First channel of pixel (x, y).
    float* at(int x, int y) { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels; }
    const float* at(int x, int y) const
    {
        return pixels.data() + (static_cast<std::size_t>(y) * width + x) * channels;
    }
};

/// What render_frame() measured.
struct RenderStats {
    long long paths = 0; ///< camera paths traced (pixels rendered × spp)
    long long rays = 0;  ///< camera, bounce and shadow rays cast
    double seconds = 0;  ///< wall time of the frame, BVH build included

    double paths_per_second() const { return seconds > 0 ? static_cast<double>(paths) / seconds : 0; }
    double rays_per_second() const { return seconds > 0 ? static_cast<double>(rays) / seconds : 0; }
};

/// All AOVs of one frame, plus its statistics.
struct FrameAovs {
    AovImage beauty;            ///< Combined, RGBA
    AovImage diffuse_direct;    ///< DiffDir, RGB
    AovImage diffuse_indirect;  ///< DiffInd, RGB
    AovImage albedo;            ///< DiffCol, RGB
    AovImage emission;          ///< Emit, RGB
    AovImage normal;            ///< Normal, XYZ
    AovImage depth;             ///< Depth, Z
    AovImage position;          ///< Position, XYZ
    AovImage indirect_variance; ///< DiffIndVar, RGB
    AovImage rendered;          ///< Rendered, one channel: 1 rendered, 0 masked out
    AovImage point_lookup;      ///< PointLookup: 4 ids then 4 weights; empty unless asked for
    RenderStats stats;

    /// Sizes every buffer for width × height and fills them with zeros; the point
    /// lookup only when `with_point_lookup` (else it is left empty).
    void reset(int width, int height, bool with_point_lookup = false);
};

/// One layer of FrameAovs with its suggested EXR names.
struct AovLayer {
    std::string name;                       ///< "Combined", "DiffInd", ...
    std::vector<std::string> channel_names; ///< "R", "G", "B", "A" / "X", "Y", "Z" / "Z" / "V"
    const AovImage* image;                  ///< the buffer (channels = channel_names.size())
};

/// Points per pixel in the PointLookup layer.
inline constexpr int kLookupPoints = 4;

/// The layers of `aovs` in a fixed order (Combined first), for writers; PointLookup
/// last, only when it was rendered.
std::vector<AovLayer> aov_layers(const FrameAovs& aovs);

} // namespace modestack::render
