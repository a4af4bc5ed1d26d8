#include "app/sequence_adapters.h"

#include <fmt/format.h>

#include <filesystem>

namespace modestack::app {

denoise::ShotShape SequenceSource::shape() const
{
    return {m_reader.frame_count(), m_reader.width(), m_reader.height(), m_reader.selected_channel_count()};
}

void SequenceSource::read_rows(int frame_index, int row_begin, int row_end, float* destination)
{
    m_reader.read_selected(frame_index, row_begin, row_end, destination);
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
    thread_local std::vector<unsigned char> native;
    native.clear();
    if (output->needs_input_rows())  // pass-through channels to copy
        m_reader.read_native(frame_index, row_begin, row_end, native);
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
