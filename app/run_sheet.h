// The last pass of `modestack run`: one read of the frames that run shows or
// measures, giving the contact sheet (noisy, denoised, refined and, with a
// reference, the reference beauty of four frames spread over the shot) and the
// per-frame relMSE of the noisy, denoised and refined results against the
// reference (docs/design.md, "How we measure quality").
#pragma once

#include "core/scene/builtin_scenes.h"
#include "io/color_management.h"
#include "io/sequence.h"

#include <optional>
#include <string>
#include <vector>

namespace modestack::app {

/// The sequences of a run, all of the same frames.
struct RunSequences {
    io::FrameSequence noisy;
    io::FrameSequence denoised;
    io::FrameSequence final_frames;
    std::optional<io::FrameSequence> reference;  ///< --reference-spp
};

/// What the pass found.
struct RunMeasurements {
    /// errors[layer][version][frame]: layer 0 DiffInd, 1 beauty; version 0 noisy,
    /// 1 denoised, 2 refined; the frames empty without a reference.
    std::vector<std::vector<std::vector<double>>> errors;
    std::vector<int> shown_frames;  ///< frame numbers on the contact sheet
};

/// Frames shown on the contact sheet (indices into `frames`): four spread over
/// the shot; when the scene has a brief event (SceneInfo::highlight_frames, e.g.
/// switch's crossing, where the denoiser fails), one of them is its middle frame.
std::vector<int> sheet_frame_indices(const std::vector<int>& frames, const scene::FrameSpan& highlight);

/// Measures against the reference (if any) and writes the contact sheet to `sheet_path` through `display`.
RunMeasurements measure_and_write_sheet(const RunSequences& sequences, const std::vector<int>& frames,
                                        const scene::FrameSpan& highlight, const io::DisplayConverter& display,
                                        const std::string& sheet_path);

}  // namespace modestack::app
