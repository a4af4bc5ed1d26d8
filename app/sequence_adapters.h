// Adapters between io's files and the denoise engine's stream ends: the source
// reads selected channels of an opened input sequence; the sink writes each
// output frame (every input channel copied, the selected ones replaced, sigma
// channels appended) and, if asked, the spatial modes.
#pragma once

#include "core/denoise/frame_stream.h"
#include "io/frame_output.h"
#include "io/sequence_reader.h"

#include <memory>
#include <string>
#include <vector>

namespace modestack::app {

/// FrameSource over an io::SequenceReader.
class SequenceSource : public denoise::FrameSource {
public:
    explicit SequenceSource(const io::SequenceReader& reader) : m_reader(reader) {}
    denoise::ShotShape shape() const override;
    void read_rows(int frame_index, int row_begin, int row_end, float* destination) override;

private:
    const io::SequenceReader& m_reader;
};

/// FrameSink writing one output file per input frame.
class SequenceSink : public denoise::FrameSink {
public:
    /// `outputs` has one path per frame ("" = skip that frame, e.g. --skip-existing).
    /// `modes_directory` ("" = none) receives mode.NN.exr per spatial mode.
    SequenceSink(const io::SequenceReader& reader, std::vector<std::string> outputs, std::string modes_directory);

    /// Attributes every output header gets (provenance), besides rank, rule and solver.
    void set_attributes(std::vector<io::HeaderAttribute> attributes) { m_attributes = std::move(attributes); }
    /// Opens every output under its temporary name.
    void begin(const denoise::RebuildStart& start) override;
    /// Renames every finished output into place.
    void commit();

    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma) override;
    void write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes) override;
    bool wants_modes() const override { return !m_modes_directory.empty(); }

private:
    const io::SequenceReader& m_reader;
    std::vector<std::string> m_paths;
    std::string m_modes_directory;
    std::vector<std::string> m_sigma_names;
    std::vector<io::HeaderAttribute> m_attributes;
    std::vector<std::unique_ptr<io::FrameOutput>> m_outputs;
    std::vector<std::unique_ptr<io::FrameOutput>> m_mode_outputs;
};

}  // namespace modestack::app
