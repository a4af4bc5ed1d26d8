// `modestack denoise --object-space POINTS`: the low-rank denoiser on the points ×
// frames matrix that `render --points` baked (core/render/point_bake.h), then
// each frame's layer rebuilt from the denoised points its pixels see (the
// PointLookup layer of the frame). The points go through the same reader, engine,
// rank rule and confidence as images; the image mode filter and the spatial
// pooling of sigma are left out, because neighbours in a point image are not
// neighbours on the surfaces: the surface filter (core/denoise/surface_filter.h)
// takes the mode filter's place, over the points' positions and normals. The frames are written like an image-space
// denoise's (every input channel kept, the layer replaced, sigma appended), so
// refine works on them unchanged.
#pragma once

#include "core/common/progress.h"
#include "core/denoise/engine.h"
#include "core/denoise/frame_stream.h"
#include "core/denoise/surface_filter.h"
#include "io/exr_codec.h"
#include "io/frame_output.h"
#include "io/sequence.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app {

/// The engine's result for every point and frame, kept in memory.
class PointStore : public denoise::FrameSink {
public:
    explicit PointStore(denoise::ShotShape shape);
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma) override;
    /// Frame `frame_index`'s values and sigma, [point][channel] (padding points at the end).
    float* values(int frame_index) { return m_values[static_cast<std::size_t>(frame_index)].data(); }
    float* sigma(int frame_index) { return m_sigma[static_cast<std::size_t>(frame_index)].data(); }

private:
    denoise::ShotShape m_shape;
    std::vector<std::vector<float>> m_values, m_sigma;
};

/// Rebuilds `pixels` pixels of a frame from `lookup` (PointLookup: kLookupPoints
/// ids then as many weights per pixel): rebuilt = Σ w·value, sigma = Σ w·sigma
/// (the points' errors are correlated, so they add linearly). `channels` values
/// per point and pixel. Throws a bad-input error naming `file` for an id that is
/// not below `point_count`.
void rebuild_from_points(const float* lookup, std::size_t pixels, const float* point_values,
                         const float* point_sigma, int channels, std::int64_t point_count, const std::string& file,
                         float* rebuilt, float* sigma);

/// One object-space job.
struct ObjectSpaceJob {
    io::FrameSequence frames;                     ///< rendered frames with PointLookup
    std::string points;                           ///< the points sequence (pattern)
    std::vector<std::string> layers;              ///< --layer, for frames and points alike
    std::vector<std::string> outputs;             ///< per frame; "" = not written
    std::vector<io::HeaderAttribute> attributes;  ///< provenance for every output
    bool surface_filter = true;                   ///< filter over the surfaces (denoise/surface_filter.h)
    std::vector<double> filter_widths;            ///< its candidate widths, in lattice spacings
    int sigma_radius = 2;                         ///< sigma's pooling window, in lattice spacings (≥ 1 used)
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec, for frames and points alike
};

/// What the job did, for the summary.
struct ObjectSpaceResult {
    denoise::Report report;     ///< the engine's, on the points
    denoise::SurfaceFilterChoice filter;  ///< what the surface filter chose (width 0: none)
    std::int64_t points = 0;    ///< surface points (from the points files)
    int frame_width = 0, frame_height = 0;
};

/// Checks everything, denoises the points and writes the frames. Throws a
/// bad-input error naming the file for a frame without PointLookup, a points
/// sequence with other frames, layers or point count.
ObjectSpaceResult run_object_space(const ObjectSpaceJob& job, denoise::Settings settings, Progress& progress);

} // namespace modestack::app
