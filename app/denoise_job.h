// `modestack denoise` as a library call: the options as typed
// (DenoiseCommandOptions), the one validation step that turns them into a
// checked DenoiseJob (engine settings, transform, method and farm-stage options),
// denoise() that runs the engine on the sequence and writes the frames (and
// --save-modes, --rank-map, --report), and the DenoiseResult it returns, which
// denoise_json() writes as the --json summary. `modestack run` fills the options
// and calls the same functions; the report page comes back in the result.
#pragma once

#include "app/denoise_stages.h"
#include "app/method_options.h"
#include "app/object_space.h"
#include "app/renderer_conventions.h"
#include "app/report/report_data.h"
#include "app/run_context.h"
#include "core/denoise/engine.h"
#include "core/denoise/transform.h"
#include "io/exr_codec.h"
#include "io/frame_output.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace modestack::app {

/// The options of `denoise` as typed.
struct DenoiseCommandOptions {
    std::string input;
    std::string output;
    std::vector<std::string> layers;
    std::string rank = "auto";
    std::string rank_rule = "press";
    std::string method = "auto";
    std::string max_memory = "auto";
    std::string frames;
    std::string save_modes;
    std::string report_path;
    bool no_firefly_clamp = false;
    double firefly_k = 6.0;
    int sigma_radius = 2;
    bool mode_filter = false;
    bool no_mode_filter = false;
    int mode_filter_modes = 16;
    std::vector<double> mode_filter_widths{0.75, 1.0, 1.5, 2.0, 3.0};
    std::vector<std::string> mode_filter_guides{"auto"};
    std::string renderer = "auto"; ///< --renderer
    std::string conventions;       ///< --conventions FILE ("" = the shipped table)
    bool update_beauty = false;    ///< --update-beauty
    bool no_update_beauty = false; ///< --no-update-beauty
    std::string rank_map;
    bool skip_existing = false;
    std::string colorspace;
    std::string ocio_config;
    std::string object_space;  ///< --object-space: the points sequence
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
    bool single_part = false;                           ///< --single-part
    bool joint = false;                                 ///< --joint: several layers share their modes
    std::string compression;    ///< --compression ("" = the input's if lossless, else zip)
    std::string data_type;      ///< --data-type half|float ("" = the input's)
    bool only_denoised = false; ///< --only-denoised
    MethodOptions method_options;
    StageOptions stage;
};

/// A denoise checked before any work, as far as the options go; what needs the
/// files (frame counts, --rank against them, output paths) denoise() checks
/// before its first read of pixels.
struct DenoiseJob {
    std::string input;
    std::string output;
    std::vector<std::string> layers;
    std::string frames;
    std::string save_modes;  ///< "" = none
    std::string report_path; ///< "" = no --report
    std::string rank_map;    ///< "" = one N for every pixel
    bool skip_existing = false;
    std::string colorspace;
    std::string ocio_config;
    std::string object_space;         ///< "" = image space
    std::string renderer = "auto";    ///< --renderer
    std::shared_ptr<const ConventionTable> conventions; ///< the table --conventions names, or the shipped one
    bool guides_required = false; ///< --mode-filter-guides named them: each must be found
    std::string update_beauty = "auto"; ///< auto, on (--update-beauty), off (--no-update-beauty)
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;
    io::PartLayout part_layout = io::PartLayout::AsInput; ///< --single-part flattens multi-part inputs
    /// Several layers share one set of modes and N (--joint, or one layer);
    /// otherwise each layer gets its own (denoise::Settings::layer_channels).
    bool joint = true;
    io::OutputFormat output_format;                       ///< --compression, --data-type, --only-denoised
    bool surface_filter = true;       ///< object space: filter over the surfaces
    std::vector<double> filter_widths;
    denoise::Settings settings;
    denoise::Transform transform;
    MethodOptions method_options;
    StageOptions stage;
    /// --stage: the denoise command whose options go into the shot's fingerprint.
    const CLI::App* stage_command = nullptr;
};

/// One denoised layer's channels, as the summary lists them.
struct DenoisedLayer {
    std::string name;
    std::vector<std::string> channels;
    std::vector<std::string> sigma;
    /// Layers apart: whether --whiten whitened this layer and why (whitened_part_json); null otherwise.
    nlohmann::ordered_json whiten;
};

/// What a denoise did: everything its --json summary holds, and the --report page.
struct DenoiseResult {
    bool nothing_to_do = false;  ///< --skip-existing found every output
    denoise::Report report;      ///< merged over --segments parts
    std::string input;           ///< printf pattern
    std::string output;          ///< -o as given
    std::vector<int> frames;     ///< the shot's frame numbers
    int frames_written = 0;
    int width = 0, height = 0;   ///< of the frames
    std::vector<std::string> channel_names;
    std::vector<DenoisedLayer> layers;
    bool joint = true; ///< the layers shared their modes (false: each has its own, report.layers)
    /// The renderer conventions used and the guide and variance layers found (renderer_json).
    nlohmann::ordered_json renderer;
    /// What --update-beauty did to the beauty, and why (beauty_json).
    nlohmann::ordered_json beauty;
    std::string rank_map;        ///< the --rank-map file
    double seconds = 0;
    std::int64_t peak_memory_bytes = 0;  ///< the process's, when the run ended
    std::int64_t max_memory_bytes = 0;
    bool non_negative = false;   ///< --non-negative was on
    bool automatic_segments = false;
    std::size_t segment_cuts = 0, segment_parts = 0;
    /// Blocks the colour, method and farm modules write from objects that live only during the run.
    nlohmann::ordered_json color, method, farm;
    /// --stage: which task ran, whether it wrote frames, whether its output stayed in memory (MPI).
    std::optional<denoise::Stage> stage;
    bool writes_frames = true;
    bool output_in_memory = false;
    /// --object-space: what the points job did (report is its engine report).
    std::optional<ObjectSpaceResult> object_space;
    std::string points_input;
    bool surface_filter = false;
    /// --report: the page's data (already written), for `run` to complete.
    std::optional<report::ReportData> report_page;
};

/// The fewest frames a shot to denoise may have (run checks its --frames against it too).
inline constexpr std::size_t kMinimumShotFrames = 3;
/// The one message for a shot of fewer frames: "denoising needs at least 3 frames, found 2".
std::string too_few_frames(std::size_t frame_count);

/// The validation step of `denoise`: usage errors, one per rule, for every
/// option value and combination. `command` (may be null) is the parsed denoise
/// command, which --stage fingerprints.
DenoiseJob make_denoise_job(const DenoiseCommandOptions& options, const CLI::App* command);

/// Denoises the sequence of `job` and writes its outputs.
DenoiseResult denoise(const DenoiseJob& job, const CommonOptions& context);

/// The --json summary of a denoise.
nlohmann::ordered_json denoise_json(const DenoiseResult& result);

/// The lines denoise prints on stderr (not with --quiet).
void print_denoise_summary(const DenoiseResult& result);

}  // namespace modestack::app
