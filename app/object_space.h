// `modestack denoise --object-space POINTS`: the wiring of object-space
// denoising. It opens the frames (with their PointLookup layer) and the points
// sequence that `render --points` baked (core/render/point_bake.h), checks that
// they belong together, reads the points' positions and normals, hands the
// points × frames matrix to core (core/objectspace/point_denoise.h) and writes
// each frame's layer rebuilt from the denoised points its pixels see
// (core/objectspace/point_rebuild.h). The frames are written like an image-space
// denoise's (every input channel kept, the layer replaced, sigma appended), so
// refine works on them unchanged.
#pragma once

#include "app/renderer_conventions.h"
#include "core/common/progress.h"
#include "core/denoise/engine.h"
#include "core/objectspace/surface_filter.h"
#include "io/exr_codec.h"
#include "io/frame_output.h"
#include "io/sequence.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace modestack::app {

/// One object-space job.
struct ObjectSpaceJob {
    io::FrameSequence frames;                     ///< rendered frames with PointLookup
    std::string points;                           ///< the points sequence (pattern)
    std::vector<std::string> layers;              ///< --layer, for frames and points alike
    std::vector<std::string> outputs;             ///< per frame; "" = not written
    std::vector<io::HeaderAttribute> attributes;  ///< provenance for every output
    bool surface_filter = true;                   ///< filter over the surfaces (objectspace/surface_filter.h)
    std::vector<double> filter_widths;            ///< its candidate widths, in lattice spacings
    int sigma_radius = 2;                         ///< sigma's pooling window, in lattice spacings (≥ 1 used)
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate; ///< --exr-codec, for frames and points alike
    /// The renderer conventions (--conventions) and --renderer the points' variance is looked for with.
    std::shared_ptr<const ConventionTable> conventions;
    std::string renderer = "auto";
    io::PartLayout part_layout = io::PartLayout::AsInput; ///< --single-part
    io::OutputFormat output_format;                       ///< --compression, --data-type, --only-denoised
};

/// What the job did, for the summary.
struct ObjectSpaceResult {
    denoise::Report report;     ///< the engine's, on the points
    objectspace::SurfaceFilterChoice filter;  ///< what the surface filter chose (width 0: none)
    std::int64_t points = 0;    ///< surface points (from the points files)
    bool points_read_again =
        false; ///< the points' input did not fit --max-memory beside the rebuild: read per frame
    int frame_width = 0, frame_height = 0;
};

/// Checks everything, denoises the points and writes the frames. Throws a
/// bad-input error naming the file for a frame without PointLookup, a points
/// sequence with other frames, layers or point count.
ObjectSpaceResult run_object_space(const ObjectSpaceJob& job, denoise::Settings settings, Progress& progress);

} // namespace modestack::app
