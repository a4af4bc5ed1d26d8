// The composite step of `modestack run` ([0017]): the beauty pass rebuilt from the
// light passes, beauty = DiffCol × (DiffDir + DiffInd) + Emit, so that a denoised
// or refined DiffInd reaches the final image. Also used by run's measurements to
// composite the denoised (not yet refined) indirect light.
#pragma once

#include "io/sequence.h"
#include "io/sequence_reader.h"

#include "core/common/progress.h"

#include <string>
#include <vector>

namespace modestack::app {

/// The layers composite() reads, in the order it expects them interleaved.
extern const std::vector<std::string> kPassLayers;

/// Every selected channel of one frame of `reader`, interleaved [row][x][channel].
std::vector<float> read_frame(const io::SequenceReader& reader, int frame_index);

/// beauty = DiffCol × (DiffDir + DiffInd) + Emit from 12 interleaved channels per
/// pixel in kPassLayers order; `indirect` replaces DiffInd when given (3 per pixel).
std::vector<float> composite(const std::vector<float>& passes, const float* indirect);

/// Writes `final_sequence`: the frames of `refined` with Combined.RGB recomposited
/// from their own passes, every other channel copied.
void write_final(const io::FrameSequence& refined, const io::FrameSequence& final_sequence, Progress& progress);

}  // namespace modestack::app
