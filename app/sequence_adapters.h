// Adapters between io's files and the denoise engine's stream ends: the source
// reads selected channels of an opened input sequence (and auxiliary layers, a
// variance or guides, found under the names the renderer conventions give,
// app/renderer_detection.h); the sink writes each
// output frame (every input channel copied, the selected ones replaced, sigma
// channels appended) and, if asked, the spatial modes.
#pragma once

#include "app/beauty_update.h"
#include "app/renderer_detection.h"
#include "core/denoise/frame_stream.h"
#include "io/frame_output.h"
#include "io/sequence_reader.h"

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace modestack::app {

/// FrameSource over an io::SequenceReader. A read that asks for the pass-through
/// rows (pass 2's) decodes a frame with other channels once: the selected
/// channels are converted from its native rows, which go into the
/// PassThroughRows for the sink to copy the rest from.
class SequenceSource : public denoise::FrameSource {
public:
    /// `candidates` are the layer names tried for each auxiliary kind, best first
    /// (auxiliary_candidates of the shot's renderer conventions).
    /// `layer_variance` has each selected layer's own variance names
    /// (layer_variance_candidates; empty: no layer is looked up on its own).
    SequenceSource(const io::SequenceReader& reader, AuxiliaryCandidates candidates,
                   std::vector<std::vector<std::vector<std::string>>> layer_variance = {});
    denoise::ShotShape shape() const override;
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   denoise::PassThroughRows* pass_through) override;
    std::int64_t band_bytes_per_row() const override;
    /// An auxiliary layer is the first of its candidates that every frame has at
    /// the frames' size (a variance: one channel per selected channel). The
    /// first query of a kind opens the sequence again for its layer; 0 when no
    /// candidate is found.
    int auxiliary_channels(denoise::Auxiliary kind) const override;
    void read_auxiliary_rows(denoise::Auxiliary kind, int frame_index, int row_begin, int row_end,
                             float* destination) override;
    /// A layer's own variance: the first of its names that every frame has at
    /// the frames' size with one channel per channel of the layer (opened at
    /// the first query); 0 when none is found.
    int layer_variance_channels(int layer) const override;
    void read_layer_variance_rows(int layer, int frame_index, int row_begin, int row_end,
                                  float* destination) override;
    /// The names layer `layer`'s own variance is looked for under, best first.
    const std::vector<std::vector<std::string>>& layer_variance_candidates(int layer) const
    {
        return m_layer_variance_candidates.at(static_cast<size_t>(layer));
    }
    /// The sequence opened for `kind`'s layer (opening it now), or nullptr when
    /// the input has none: for the memory budget, which counts its open files.
    const io::SequenceReader* auxiliary_reader(denoise::Auxiliary kind) const;
    /// The names `kind` is looked for under, best first.
    const std::vector<std::vector<std::string>>& auxiliary_candidates(denoise::Auxiliary kind) const
    {
        return m_candidates[static_cast<size_t>(kind)];
    }
    /// Each kind looked up so far: where it was looked for and what was found (--json).
    std::vector<AuxiliaryFound> auxiliary_lookups() const;

private:
    struct AuxiliaryInput {
        bool looked = false;
        int channels = 0;
        std::vector<std::string> found; ///< the layers read
        std::unique_ptr<io::SequenceReader> reader;
    };
    const AuxiliaryInput& auxiliary(denoise::Auxiliary kind) const;
    const AuxiliaryInput& layer_variance(int layer) const;
    // Opens the first of `candidates` every frame has at the frames' size with `channels` channels (0: any).
    void look_up(AuxiliaryInput& input, const std::vector<std::vector<std::string>>& candidates,
                 int channels) const;

    const io::SequenceReader& m_reader;
    AuxiliaryCandidates m_candidates;
    std::vector<std::vector<std::vector<std::string>>> m_layer_variance_candidates;
    mutable std::mutex m_auxiliary_mutex;
    mutable std::array<AuxiliaryInput, 4> m_auxiliary;  // by denoise::Auxiliary
    mutable std::vector<AuxiliaryInput> m_layer_variance; // by selected layer
    AuxiliaryInput m_no_input;                            // a layer without names
};

/// FrameSink writing one output file per input frame.
class SequenceSink : public denoise::FrameSink {
public:
    /// `outputs` has one path per frame ("" = skip that frame, e.g. --skip-existing).
    /// `modes_directory` ("" = none) receives mode.NN.exr per spatial mode. The
    /// copies are encoded with `reader`'s ExrCodec (--exr-codec).
    SequenceSink(const io::SequenceReader& reader, std::vector<std::string> outputs, std::string modes_directory);

    /// Attributes every output header gets (provenance), besides rank, rule and solver.
    void set_attributes(std::vector<io::HeaderAttribute> attributes) { m_attributes = std::move(attributes); }
    /// --single-part: a multi-part input's outputs in one part (default: its parts).
    void set_part_layout(io::PartLayout layout) { m_part_layout = layout; }
    /// --compression, --data-type, --only-denoised (the channels --update-beauty
    /// rewrites are added to what --only-denoised keeps by update_beauty()).
    void set_output_format(io::OutputFormat format);
    /// --rank-map: also writes the per-pixel rank to `path` (one channel "rank").
    void write_rank_map_to(std::string path) { m_rank_map_path = std::move(path); }
    /// --update-beauty: rewrites the beauty (and product AOVs) in the copied rows
    /// and appends the beauty's sigma channels. Before begin().
    void update_beauty(std::unique_ptr<BeautyUpdate> update);
    /// Bytes the outputs begin() opens will hold while they are written
    /// (io::copy_buffer_bytes of each, as set up so far).
    std::int64_t open_output_bytes() const;
    /// Opens every output under its temporary name.
    void begin(const denoise::RebuildStart& start) override;
    /// Renames every finished output into place.
    void commit();

    /// Copies the other channels from `pass_through` when it holds these rows,
    /// else decodes them from the input (a kept shot's pass 2 reads nothing).
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const denoise::PassThroughRows* pass_through) override;
    void write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes) override;
    bool wants_modes() const override { return !m_modes_directory.empty(); }
    bool writes_frame(int frame_index) const override { return !m_paths[static_cast<size_t>(frame_index)].empty(); }
    void write_rank_rows(int row_begin, int row_end, const float* ranks) override;

private:
    const io::SequenceReader& m_reader;
    std::vector<std::string> m_paths;
    std::string m_modes_directory;
    std::vector<std::string> m_sigma_names;
    std::vector<io::HeaderAttribute> m_attributes;
    io::PartLayout m_part_layout = io::PartLayout::AsInput;
    io::OutputFormat m_format;
    std::vector<std::unique_ptr<io::FrameOutput>> m_outputs;
    std::vector<std::unique_ptr<io::FrameOutput>> m_mode_outputs;
    std::string m_rank_map_path;
    std::unique_ptr<io::FrameOutput> m_rank_map;
    std::unique_ptr<BeautyUpdate> m_beauty;
};

}  // namespace modestack::app
