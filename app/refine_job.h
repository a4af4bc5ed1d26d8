// `modestack refine` as a library call: the options as typed
// (RefineCommandOptions), the one validation step that turns them into a
// checked RefineJob, refine() that re-renders the unsure pixels and writes the
// refined frames (and masks), and the RefineResult it returns, which
// refine_json() writes as the --json summary. `modestack run` fills the options
// and calls the same functions. For any other renderer the loop is cut in two
// around the render (refine_external.cpp): refine_masks_only() writes the
// masks and crop windows to render, refine_blend() blends what was rendered.
#pragma once

#include "app/run_context.h"
#include "core/refine/crop_windows.h"
#include "core/refine/refine_frame.h"
#include "io/exr_codec.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app {

/// --window-overhead by default: what one more crop window costs, in pixels.
/// One 64×64 bucket: a window smaller than a bucket still pays a bucket's setup
/// and filter margin. A separate render job per window costs far more (scene
/// load, acceleration structure): measure t0 / (seconds per pixel) and pass it.
inline constexpr std::int64_t kDefaultWindowOverheadPixels = 64 * 64;

/// In a --blend pattern, the index of a crop window in --windows (one file per window).
inline constexpr const char* kWindowToken = "{window}";

/// --threshold when no other selection is given.
inline constexpr double kDefaultRefineThreshold = 0.2;

/// How refine picks its pixels (core/refine/selection.h).
enum class RefineSelection {
    Threshold, ///< --threshold (the default): relative sigma at least this
    Budget,    ///< --budget: the P % of the shot's pixels with the largest relative sigma
    Gain,      ///< --by-gain: where a re-render removes more error than its samples spread over the shot
};

/// "gain", "threshold" or "budget", as the JSON summaries say.
const char* selection_name(RefineSelection selection);

/// Which half of the refine loop a run does.
enum class RefineMode {
    Render,    ///< choose, re-render with the built-in tracer, blend (one run)
    MasksOnly, ///< choose: write the masks and crop windows for another renderer
    Blend,     ///< blend another renderer's re-render by the masks' weights
};

/// The options of `refine` as typed.
struct RefineCommandOptions {
    RefineCommandOptions()
    {
        settings.render.spp = 256;
        settings.render.seed = 2;
    }
    std::string scene;
    std::string denoised;
    std::string output;
    std::string frames;
    std::string size = "320x240";
    std::string layer = "DiffInd";
    std::string masks;
    double threshold = 0; ///< > 0: select by it (--threshold); neither this, --budget nor --by-gain: 0.2
    double budget_percent = -1; ///< ≥ 0: select by it (--budget)
    bool by_gain = false;       ///< --by-gain
    refine::RefineSettings settings;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
    bool masks_only = false;                            ///< --masks-only
    std::string windows;                                ///< --windows JSON
    std::int64_t window_overhead = kDefaultWindowOverheadPixels;
    std::string blend;          ///< --blend: the re-rendered sequence
    std::string blend_layer;    ///< --blend-layer ("" = --layer)
    std::string blend_variance; ///< --blend-variance ("" = <blend layer>Var)
};

/// A refine checked before any work (the files are checked by refine() before its first frame).
struct RefineJob {
    std::string scene;
    int scene_first_frame = 1, scene_last_frame = 1;
    std::string denoised;
    std::string output;
    std::string frames;
    std::string size;      ///< as typed, for messages
    std::string layer;
    std::string masks;     ///< "" = no mask output
    RefineSelection selection = RefineSelection::Threshold;
    double threshold = 0;       ///< Threshold
    double budget_percent = -1; ///< Budget
    refine::RefineSettings settings;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
    RefineMode mode = RefineMode::Render;
    std::string windows; ///< MasksOnly: crop-window JSON ("" = none)
    std::int64_t window_overhead = kDefaultWindowOverheadPixels;
    std::string blend;          ///< Blend: the re-rendered sequence
    std::string blend_layer;    ///< Blend: its layer
    std::string blend_variance; ///< Blend: its variance layer
};

/// One refined frame.
struct RefinedFrame {
    int frame = 0;
    refine::FrameRefineReport report;
};

/// What a refine did: everything its --json summary holds.
struct RefineResult {
    std::string scene;
    std::string input;   ///< printf pattern
    std::string output;  ///< printf pattern
    std::vector<int> frames;
    std::string layer;   ///< the layer as found in the files
    int spp = 0;
    RefineSelection selection = RefineSelection::Threshold;
    double budget_percent = -1; ///< Budget: the percentage
    float threshold = 0;        ///< the threshold used, of the selection's score (+inf: nothing selected)
    int input_spp = 0;          ///< Gain: the input's spp the frames record
    int dilate = 0;
    int feather = 0;
    std::int64_t pixels_selected = 0;
    std::int64_t pixels_rendered = 0;
    double percent_rendered = 0;
    std::int64_t paths = 0;
    double estimated_relmse_before = 0;  ///< mean over the frames
    double estimated_relmse_after = 0;
    double seconds_scoring = 0;
    double seconds_render = 0;
    double seconds_total = 0;
    std::vector<RefinedFrame> per_frame;
};

/// One frame of refine_masks_only().
struct MaskedFrame {
    int frame = 0;
    std::string mask_file;
    refine::FrameRefineReport report; ///< the choice (nothing rendered)
    std::vector<refine::PixelWindow> windows;
};

/// What refine_masks_only() did: the --windows document.
struct RefineMasksResult {
    std::string input; ///< printf pattern
    std::string masks; ///< printf pattern
    std::vector<int> frames;
    std::string layer;
    int width = 0, height = 0;
    RefineSelection selection = RefineSelection::Threshold;
    double budget_percent = -1;
    float threshold = 0;
    refine::RefineSettings settings; ///< floor and feather used
    std::int64_t window_overhead = 0;
    std::int64_t pixels_to_render = 0; ///< weight > 0, all frames
    std::int64_t window_pixels = 0;    ///< Σ window areas, all frames
    std::int64_t window_count = 0;
    double seconds_total = 0;
    std::vector<MaskedFrame> per_frame;
};

/// One frame of refine_blend().
struct BlendedFrame {
    int frame = 0;
    std::vector<std::string> sources; ///< the re-rendered files
    refine::FrameRefineReport report;
};

/// What refine_blend() did: its --json summary.
struct RefineBlendResult {
    std::string input, masks, blend, output; ///< printf patterns
    std::vector<int> frames;
    std::string layer, blend_layer, blend_variance;
    std::int64_t pixels_blended = 0;
    double percent_blended = 0;
    double estimated_relmse_before = 0; ///< mean over the frames
    double estimated_relmse_after = 0;
    double seconds_total = 0;
    std::vector<BlendedFrame> per_frame;
};

/// The validation step of `refine`: usage errors for a missing --scene,
/// --denoised or -o, a bad size, spp, depth, dilation or feather, a budget over
/// 100 %, a negative threshold, an unknown scene; for --masks-only a missing
/// --masks or a -o; for --blend a missing --masks or -o, or selection options.
RefineJob make_refine_job(const RefineCommandOptions& options);

/// Re-renders the unsure pixels of `job` and writes the refined frames and masks.
RefineResult refine(const RefineJob& job, const CommonOptions& context);

/// The --json summary of a refine.
nlohmann::ordered_json refine_json(const RefineResult& result);

/// The line refine prints on stderr.
void print_refine_summary(const RefineResult& result);

/// --masks-only: chooses the pixels to re-render as refine() would and writes
/// their masks and (with --windows) the crop windows; renders nothing.
RefineMasksResult refine_masks_only(const RefineJob& job, const CommonOptions& context);

/// The --windows document (and --masks-only's --json summary).
nlohmann::ordered_json refine_windows_json(const RefineMasksResult& result);

/// The line --masks-only prints on stderr.
void print_masks_summary(const RefineMasksResult& result);

/// --blend: blends the re-rendered layer of `job.blend` into the denoised
/// frames by the masks' weights, as refine() blends its own render.
RefineBlendResult refine_blend(const RefineJob& job, const CommonOptions& context);

/// The --json summary of --blend.
nlohmann::ordered_json refine_blend_json(const RefineBlendResult& result);

/// The line --blend prints on stderr.
void print_blend_summary(const RefineBlendResult& result);

}  // namespace modestack::app
