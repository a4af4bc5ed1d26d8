// `modestack refine` as a library call: the options as typed
// (RefineCommandOptions), the one validation step that turns them into a
// checked RefineJob, refine() that re-renders the unsure pixels and writes the
// refined frames (and masks), and the RefineResult it returns, which
// refine_json() writes as the --json summary. `modestack run` fills the options
// and calls the same functions.
#pragma once

#include "app/run_context.h"
#include "core/refine/refine_frame.h"
#include "io/exr_codec.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::app {

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
    double threshold = 0.2;
    double budget_percent = -1;  ///< < 0: use the threshold
    refine::RefineSettings settings;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
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
    double threshold = 0;
    double budget_percent = -1;  ///< < 0: use the threshold
    refine::RefineSettings settings;
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
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
    double budget_percent = -1;  ///< < 0: selected by threshold
    float threshold = 0;         ///< the threshold used (+inf: nothing selected)
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

/// The validation step of `refine`: usage errors for a missing --scene,
/// --denoised or -o, a bad size, spp, depth, dilation or feather, a budget over
/// 100 %, a threshold not above 0, an unknown scene.
RefineJob make_refine_job(const RefineCommandOptions& options);

/// Re-renders the unsure pixels of `job` and writes the refined frames and masks.
RefineResult refine(const RefineJob& job, const CommonOptions& context);

/// The --json summary of a refine.
nlohmann::ordered_json refine_json(const RefineResult& result);

/// The line refine prints on stderr.
void print_refine_summary(const RefineResult& result);

}  // namespace modestack::app
