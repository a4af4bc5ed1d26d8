// Adapters between io's files and the denoise engine's stream ends: the source
// reads selected channels of an opened input sequence (and auxiliary layers, a
// variance or guides, found by name next to them); the sink writes each
// output frame (every input channel copied, the selected ones replaced, sigma
// channels appended) and, if asked, the spatial modes.
#pragma once

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

/// FrameSource over an io::SequenceReader. Once the sink starts writing, a
/// frame with pass-through channels is decoded once per band: the source keeps
/// its native rows, converts the selected channels from them, and the sink copies
/// the rest from the same rows instead of decoding the file a second time.
class SequenceSource : public denoise::FrameSource {
public:
    explicit SequenceSource(const io::SequenceReader& reader);
    denoise::ShotShape shape() const override;
    void read_rows(int frame_index, int row_begin, int row_end, float* destination) override;
    std::int64_t band_bytes_per_row() const override;
    /// Auxiliary layers are found by name next to the first selected layer `L`
    /// (prefix `P.` of `P.L`, none for a bare `L`): Variance `<L>Var` for each
    /// selected layer (our renderer's `DiffIndVar`), Albedo `P.DiffCol` or
    /// `P.Denoising Albedo`, Normal `P.Normal` or `P.Denoising Normal`, Depth
    /// `P.Depth` or `P.Denoising Depth`. The first query of a kind opens the
    /// sequence again for its layer; 0 when no frame-consistent layer is found.
    int auxiliary_channels(denoise::Auxiliary kind) const override;
    void read_auxiliary_rows(denoise::Auxiliary kind, int frame_index, int row_begin, int row_end,
                             float* destination) override;
    /// The sequence opened for `kind`'s layer (opening it now), or nullptr when
    /// the input has none: for the memory budget, which counts its open files.
    const io::SequenceReader* auxiliary_reader(denoise::Auxiliary kind) const;

    /// Starts keeping the native rows of each read of a frame with pass-through channels.
    void keep_native_rows() { m_keeping = true; }
    /// The kept native rows [row_begin, row_end) of frame `frame_index`, or
    /// nullptr when the last read of that frame did not cover them.
    const unsigned char* native_rows(int frame_index, int row_begin, int row_end) const;

private:
    struct NativeRows {
        int row_begin = 0;
        int row_end = 0;
        std::vector<unsigned char> bytes;
    };
    struct AuxiliaryInput {
        bool looked = false;
        int channels = 0;
        std::unique_ptr<io::SequenceReader> reader;
    };
    const AuxiliaryInput& auxiliary(denoise::Auxiliary kind) const;

    const io::SequenceReader& m_reader;
    bool m_keeping = false;
    std::vector<NativeRows> m_native;  // per frame
    mutable std::mutex m_auxiliary_mutex;
    mutable std::array<AuxiliaryInput, 4> m_auxiliary;  // by denoise::Auxiliary
};

/// FrameSink writing one output file per input frame.
class SequenceSink : public denoise::FrameSink {
public:
    /// `outputs` has one path per frame ("" = skip that frame, e.g. --skip-existing).
    /// `modes_directory` ("" = none) receives mode.NN.exr per spatial mode. The
    /// copies are encoded with `reader`'s ExrCodec (--exr-codec).
    SequenceSink(const io::SequenceReader& reader, std::vector<std::string> outputs, std::string modes_directory);

    /// Takes pass-through channels from the rows `source` decoded for the same
    /// band (see SequenceSource) instead of decoding them again.
    void reuse_rows_of(SequenceSource& source) { m_source = &source; }
    /// Attributes every output header gets (provenance), besides rank, rule and solver.
    void set_attributes(std::vector<io::HeaderAttribute> attributes) { m_attributes = std::move(attributes); }
    /// --rank-map: also writes the per-pixel rank to `path` (one channel "rank").
    void write_rank_map_to(std::string path) { m_rank_map_path = std::move(path); }
    /// Opens every output under its temporary name.
    void begin(const denoise::RebuildStart& start) override;
    /// Renames every finished output into place.
    void commit();

    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma) override;
    void write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes) override;
    bool wants_modes() const override { return !m_modes_directory.empty(); }
    bool writes_frame(int frame_index) const override { return !m_paths[static_cast<size_t>(frame_index)].empty(); }
    void write_rank_rows(int row_begin, int row_end, const float* ranks) override;

private:
    const io::SequenceReader& m_reader;
    SequenceSource* m_source = nullptr;
    std::vector<std::string> m_paths;
    std::string m_modes_directory;
    std::vector<std::string> m_sigma_names;
    std::vector<io::HeaderAttribute> m_attributes;
    std::vector<std::unique_ptr<io::FrameOutput>> m_outputs;
    std::vector<std::unique_ptr<io::FrameOutput>> m_mode_outputs;
    std::string m_rank_map_path;
    std::unique_ptr<io::FrameOutput> m_rank_map;
};

}  // namespace modestack::app
