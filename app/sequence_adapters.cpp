#include "app/sequence_adapters.h"

#include <fmt/format.h>

#include <filesystem>

namespace modestack::app {

denoise::ShotShape SequenceSource::shape() const
{
    return {m_reader.frame_count(), m_reader.width(), m_reader.height(), m_reader.selected_channel_count()};
}

SequenceSource::SequenceSource(const io::SequenceReader& reader)
    : m_reader(reader), m_native(static_cast<size_t>(reader.frame_count()))
{
}

void SequenceSource::read_rows(int frame_index, int row_begin, int row_end, float* destination)
{
    // A read of the whole height is a kept shot's single read (never a streamed band,
    // see band_plan.h): its pass 2 reads nothing, so keeping its rows would only hold
    // a second copy of the shot (segmented runs start later parts after a sink began).
    const bool whole_frame = row_begin == 0 && row_end == m_reader.height();
    if (!m_keeping || whole_frame || !m_reader.has_unselected_channels(frame_index)) {
        m_reader.read_selected(frame_index, row_begin, row_end, destination);
        return;
    }
    NativeRows& native = m_native[static_cast<size_t>(frame_index)];
    m_reader.read_native(frame_index, row_begin, row_end, native.bytes);
    native.row_begin = row_begin;
    native.row_end = row_end;
    m_reader.selected_from_native(frame_index, native.bytes.data(),
                                  static_cast<size_t>(m_reader.width()) * (row_end - row_begin), destination);
}

std::int64_t SequenceSource::band_bytes_per_row() const
{
    std::int64_t bytes = 0;
    for (int frame = 0; frame < m_reader.frame_count(); ++frame)
        if (m_reader.has_unselected_channels(frame))
            bytes += static_cast<std::int64_t>(m_reader.native_pixel_bytes(frame)) * m_reader.width();
    return bytes;
}

const unsigned char* SequenceSource::native_rows(int frame_index, int row_begin, int row_end) const
{
    const NativeRows& native = m_native[static_cast<size_t>(frame_index)];
    if (!m_keeping || native.bytes.empty() || row_begin < native.row_begin || row_end > native.row_end)
        return nullptr;
    return native.bytes.data() +
           m_reader.native_pixel_bytes(frame_index) * m_reader.width() * static_cast<size_t>(row_begin - native.row_begin);
}

SequenceSink::SequenceSink(const io::SequenceReader& reader, std::vector<std::string> outputs,
                           std::string modes_directory)
    : m_reader(reader), m_paths(std::move(outputs)), m_modes_directory(std::move(modes_directory))
{
    for (const auto& layer : reader.layers())
        m_sigma_names.insert(m_sigma_names.end(), layer.sigma_names.begin(), layer.sigma_names.end());
}

void SequenceSink::begin(const denoise::RebuildStart& start)
{
    std::vector<io::HeaderAttribute> attributes = m_attributes;
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:rank", start.rank));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:rank_rule", start.rank_rule));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:solver", start.solver));
    if (m_source)  // pass 2's reads start now: keep what they decode for the copies
        m_source->keep_native_rows();
    m_outputs.clear();
    for (size_t frame = 0; frame < m_paths.size(); ++frame)
        m_outputs.push_back(m_paths[frame].empty() ? nullptr
                                                   : std::make_unique<io::FrameOutput>(
                                                         m_paths[frame], m_reader, static_cast<int>(frame),
                                                         m_sigma_names, attributes));
}

void SequenceSink::commit()
{
    for (auto& output : m_outputs)
        if (output)
            output->commit();
    for (auto& output : m_mode_outputs)
        output->commit();
}

void SequenceSink::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma)
{
    io::FrameOutput* output = m_outputs.at(frame_index).get();
    if (!output)
        return;
    const unsigned char* native = nullptr;
    if (output->needs_input_rows()) {  // pass-through channels to copy
        native = m_source ? m_source->native_rows(frame_index, row_begin, row_end) : nullptr;
        if (!native) {  // a kept shot: pass 2 did not read the file
            thread_local std::vector<unsigned char> decoded;
            m_reader.read_native(frame_index, row_begin, row_end, decoded);
            native = decoded.data();
        }
    }
    output->write_replaced_rows(row_begin, row_end, native, rebuilt, sigma);
}

void SequenceSink::write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes)
{
    if (m_mode_outputs.empty()) {
        io::NewImageDescription image;
        image.width = m_reader.width();
        image.height = m_reader.height();
        image.channel_names = m_reader.selected_channel_names();
        image.channel_types.assign(image.channel_names.size(), "float");
        for (int j = 0; j < modes; ++j) {
            std::string path = (std::filesystem::path(m_modes_directory) / fmt::format("mode.{:02d}.exr", j + 1)).string();
            m_mode_outputs.push_back(std::make_unique<io::FrameOutput>(
                path, image, std::vector<io::HeaderAttribute>{io::HeaderAttribute::of_integer("modestack:mode", j + 1)}));
        }
    }
    std::size_t samples = static_cast<std::size_t>(m_reader.width()) * (row_end - row_begin) *
                          m_reader.selected_channel_count();
    for (int j = 0; j < modes; ++j)
        m_mode_outputs[j]->write_float_rows(row_begin, row_end, spatial_modes + j * samples);
}

}  // namespace modestack::app
