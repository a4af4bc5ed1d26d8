// What the three modes of `modestack refine` share (refine_job.h): the check
// that a sequence is a denoiser's output with sigma, the frame-by-frame buffers
// of the layer and its sigma, the shot-wide --budget and --by-gain thresholds
// (and the input's spp the latter needs), and the mask
// frames refine writes. One place for each, so that the in-process refine,
// --masks-only and --blend read, choose and write alike.
#pragma once

#include "core/common/progress.h"
#include "core/refine/refine_frame.h"
#include "io/frame_output.h"
#include "io/sequence_reader.h"

#include <memory>
#include <string>
#include <vector>

namespace modestack::app {

/// Throws a bad-input error naming `file` unless it has `<layer>.sigma` channels.
void check_sigma_channels(const std::string& file, const std::string& layer);

/// Throws a bad-input error naming the first frame unless the reader's layer
/// and its sigma each have exactly 3 channels.
void check_colour_layers(const io::SequenceReader& reader);

/// One frame's layer and sigma as refine works on them: `rows` as the reader
/// interleaves them (layer then sigma, 6 floats a pixel), `value` and `sigma`
/// as 3 floats a pixel each.
struct LayerAndSigma {
    explicit LayerAndSigma(std::size_t pixel_count);
    /// Reads frame `frame_index` into rows, value and sigma.
    void read(const io::SequenceReader& reader, int frame_index);
    /// The same from the frame's native rows (SequenceReader::read_native), not decoding it again.
    void from_native(const io::SequenceReader& reader, int frame_index, const unsigned char* native);
    /// Puts value and sigma back into rows, for FrameOutput::write_replaced_rows.
    void store();
    std::size_t pixels;
    std::vector<float> rows, value, sigma;

private:
    void split_rows(); ///< rows (value and sigma interleaved per pixel) into value and sigma
};

/// --budget: one read of every frame to find the score threshold that selects
/// `budget_percent` % of the shot's pixels (selection.h). Adds its wall time to `seconds`.
float budget_threshold(const io::SequenceReader& reader, double budget_percent, float dark_floor,
                       Progress& progress, double& seconds);

/// Refine by gain: one read of every frame for the relMSE that sigma predicts
/// over the shot, and from it the least gain a re-render pays for
/// (refine::gain_threshold). Adds its wall time to `seconds`.
float gain_threshold_of_shot(const io::SequenceReader& reader, const refine::RefineSettings& settings,
                             Progress& progress, double& seconds);

/// Refine by gain: the input's spp that `file` records (modestack:spp, which
/// modestack's renders write and denoise keeps) after checking that it has the
/// input's variance `<layer>Var`. Throws a bad-input error naming the file,
/// and saying to pass --threshold or --budget, when either is missing.
int recorded_input_spp(const std::string& file, const std::string& layer);

/// Appends to `outputs` the mask frame of `weights` (width·height): channel
/// "mask" (half, 1 where weight > 0: to be re-rendered; what `render --mask`
/// and a compositor's matte read) and "weight" (float, the exact blend weight
/// that `refine --blend` reads back).
void add_mask_output(std::vector<std::unique_ptr<io::FrameOutput>>& outputs, const std::string& file,
                     const std::vector<float>& weights, int width, int height,
                     const std::vector<io::HeaderAttribute>& attributes);

} // namespace modestack::app
