#include "app/sequence_adapters.h"

#include "app/command.h"
#include "core/common/error.h"

#include <fmt/format.h>

#include <filesystem>

namespace modestack::app {

denoise::ShotShape SequenceSource::shape() const
{
    return {m_reader.frame_count(), m_reader.width(), m_reader.height(), m_reader.selected_channel_count()};
}

SequenceSource::SequenceSource(const io::SequenceReader& reader, AuxiliaryCandidates candidates,
                               std::vector<std::vector<std::vector<std::string>>> layer_variance)
    : m_reader(reader), m_candidates(std::move(candidates)),
      m_layer_variance_candidates(std::move(layer_variance)),
      m_layer_variance(m_layer_variance_candidates.size())
{
}

void SequenceSource::read_rows(int frame_index, int row_begin, int row_end, float* destination,
                               denoise::PassThroughRows* pass_through)
{
    if (!pass_through || !m_reader.has_unselected_channels(frame_index)) {
        if (pass_through)
            pass_through->bytes.clear();
        m_reader.read_selected(frame_index, row_begin, row_end, destination);
        return;
    }
    m_reader.read_native(frame_index, row_begin, row_end, pass_through->bytes);
    pass_through->row_begin = row_begin;
    pass_through->row_end = row_end;
    m_reader.selected_from_native(frame_index, pass_through->bytes.data(),
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

void SequenceSource::look_up(AuxiliaryInput& input, const std::vector<std::vector<std::string>>& candidates,
                             int channels) const
{
    input.looked = true;
    for (const std::vector<std::string>& selectors : candidates) {
        try {
            auto reader = std::make_unique<io::SequenceReader>(m_reader.sequence(), selectors, m_reader.exr_codec());
            if (reader->width() != m_reader.width() || reader->height() != m_reader.height())
                continue;
            if (channels > 0 && reader->selected_channel_count() != channels)
                continue;
            input.channels = reader->selected_channel_count();
            for (const io::SelectedLayer& layer : reader->layers())
                input.found.push_back(layer.name);
            input.reader = std::move(reader);
            return;
        } catch (const Error&) {
            // Not in every frame (or not at all): try the next name.
        }
    }
}

const SequenceSource::AuxiliaryInput& SequenceSource::auxiliary(denoise::Auxiliary kind) const
{
    std::lock_guard<std::mutex> lock(m_auxiliary_mutex);
    AuxiliaryInput& input = m_auxiliary[static_cast<size_t>(kind)];
    // A variance per selected channel, in the same component order.
    if (!input.looked)
        look_up(input, m_candidates[static_cast<size_t>(kind)],
                kind == denoise::Auxiliary::Variance ? m_reader.selected_channel_count() : 0);
    return input;
}

const SequenceSource::AuxiliaryInput& SequenceSource::layer_variance(int layer) const
{
    std::lock_guard<std::mutex> lock(m_auxiliary_mutex);
    if (layer < 0 || static_cast<size_t>(layer) >= m_layer_variance.size())
        return m_no_input;
    AuxiliaryInput& input = m_layer_variance[static_cast<size_t>(layer)];
    // A variance per channel of the layer, in the same component order.
    if (!input.looked)
        look_up(input, m_layer_variance_candidates[static_cast<size_t>(layer)],
                static_cast<int>(m_reader.layers()[static_cast<size_t>(layer)].channel_names.size()));
    return input;
}

int SequenceSource::layer_variance_channels(int layer) const
{
    return layer_variance(layer).channels;
}

void SequenceSource::read_layer_variance_rows(int layer, int frame_index, int row_begin, int row_end,
                                              float* destination)
{
    const AuxiliaryInput& input = layer_variance(layer);
    if (!input.reader)
        throw internal_error("a layer's variance was read that the input does not have");
    input.reader->read_selected(frame_index, row_begin, row_end, destination);
}

std::vector<AuxiliaryFound> SequenceSource::auxiliary_lookups() const
{
    std::lock_guard<std::mutex> lock(m_auxiliary_mutex);
    std::vector<AuxiliaryFound> lookups;
    for (size_t kind = 0; kind < m_auxiliary.size(); ++kind)
        if (m_auxiliary[kind].looked)
            lookups.push_back(
                {static_cast<denoise::Auxiliary>(kind), "", m_candidates[kind], m_auxiliary[kind].found});
    for (size_t layer = 0; layer < m_layer_variance.size(); ++layer)
        if (m_layer_variance[layer].looked)
            lookups.push_back({denoise::Auxiliary::Variance, m_reader.layers()[layer].name,
                               m_layer_variance_candidates[layer], m_layer_variance[layer].found});
    return lookups;
}

int SequenceSource::auxiliary_channels(denoise::Auxiliary kind) const { return auxiliary(kind).channels; }

const io::SequenceReader* SequenceSource::auxiliary_reader(denoise::Auxiliary kind) const
{
    return auxiliary(kind).reader.get();
}

void SequenceSource::read_auxiliary_rows(denoise::Auxiliary kind, int frame_index, int row_begin, int row_end,
                                         float* destination)
{
    const AuxiliaryInput& input = auxiliary(kind);
    if (!input.reader)
        throw internal_error("an auxiliary layer was read that the input does not have");
    input.reader->read_selected(frame_index, row_begin, row_end, destination);
}

SequenceSink::SequenceSink(const io::SequenceReader& reader, std::vector<std::string> outputs,
                           std::string modes_directory)
    : m_reader(reader), m_paths(std::move(outputs)), m_modes_directory(std::move(modes_directory))
{
    for (const auto& layer : reader.layers())
        m_sigma_names.insert(m_sigma_names.end(), layer.sigma_names.begin(), layer.sigma_names.end());
}

void SequenceSink::update_beauty(std::unique_ptr<BeautyUpdate> update)
{
    m_beauty = std::move(update);
    const std::vector<std::string>& names = m_beauty->plan().sigma_names;
    m_sigma_names.insert(m_sigma_names.end(), names.begin(), names.end());
    m_format.kept_layers = rewritten_layers(m_beauty->plan());
}

void SequenceSink::set_output_format(io::OutputFormat format)
{
    format.kept_layers = m_format.kept_layers; // what update_beauty() said
    m_format = std::move(format);
}

std::int64_t SequenceSink::open_output_bytes() const
{
    std::int64_t bytes = 0;
    for (size_t frame = 0; frame < m_paths.size(); ++frame)
        if (!m_paths[frame].empty())
            bytes += io::copy_buffer_bytes(m_reader, static_cast<int>(frame), m_sigma_names,
                                           m_reader.exr_codec(), m_part_layout, m_format);
    return bytes;
}

void SequenceSink::begin(const denoise::RebuildStart& start)
{
    std::vector<io::HeaderAttribute> attributes = m_attributes;
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:rank", start.kept_modes));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:rank_rule", start.rank_rule));
    attributes.push_back(io::HeaderAttribute::of_text("modestack:solver", start.solver));
    if (start.layer_modes.size() == m_reader.layers().size()) { // each layer on its own modes
        std::string ranks;
        for (size_t i = 0; i < start.layer_modes.size(); ++i)
            ranks += fmt::format("{}{}={}", i ? "," : "", m_reader.layers()[i].name, start.layer_modes[i]);
        attributes.push_back(io::HeaderAttribute::of_text("modestack:layer_ranks", ranks));
    }
    m_outputs.clear();
    for (size_t frame = 0; frame < m_paths.size(); ++frame)
        m_outputs.push_back(m_paths[frame].empty()
                                ? nullptr
                                : std::make_unique<io::FrameOutput>(
                                      m_paths[frame], m_reader, static_cast<int>(frame), m_sigma_names,
                                      attributes, m_reader.exr_codec(), m_part_layout, m_format));
}

void SequenceSink::commit()
{
    for (auto& output : m_outputs)
        if (output)
            output->commit();
    for (auto& output : m_mode_outputs)
        output->commit();
    if (m_rank_map)
        m_rank_map->commit();
}

void SequenceSink::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt,
                              const float* sigma, const denoise::PassThroughRows* pass_through)
{
    io::FrameOutput* output = m_outputs.at(frame_index).get();
    if (!output)
        return;
    const unsigned char* native = nullptr;
    if (output->needs_input_rows()) {  // pass-through channels to copy
        const std::size_t row_bytes = m_reader.native_pixel_bytes(frame_index) * m_reader.width();
        native = pass_through ? pass_through->rows(row_begin, row_end, row_bytes) : nullptr;
        if (!native) {  // a kept shot: pass 2 did not read the file
            thread_local std::vector<unsigned char> decoded;
            m_reader.read_native(frame_index, row_begin, row_end, decoded);
            native = decoded.data();
        }
    }
    if (m_beauty && native) { // the beauty is written from a copy of the rows, the noisy layers still in it
        const std::size_t pixels = static_cast<std::size_t>(m_reader.width()) * (row_end - row_begin);
        const std::size_t row_bytes = m_reader.native_pixel_bytes(frame_index) * m_reader.width();
        thread_local std::vector<unsigned char> updated;
        updated.assign(native, native + row_bytes * (row_end - row_begin));
        // The extra channels per pixel: the layers' sigma, then the beauty's.
        const std::size_t selected = static_cast<std::size_t>(m_reader.selected_channel_count());
        const std::size_t beauty_sigmas = m_beauty->plan().sigma_names.size();
        thread_local std::vector<float> beauty_sigma, extra;
        beauty_sigma.resize(pixels * beauty_sigmas);
        m_beauty->apply(frame_index, pixels, updated.data(), rebuilt, sigma, beauty_sigma.data());
        extra.resize(pixels * (selected + beauty_sigmas));
        for (std::size_t p = 0; p < pixels; ++p) {
            for (std::size_t c = 0; c < selected; ++c)
                extra[p * (selected + beauty_sigmas) + c] = sigma ? sigma[p * selected + c] : 0.0f;
            for (std::size_t c = 0; c < beauty_sigmas; ++c)
                extra[p * (selected + beauty_sigmas) + selected + c] = beauty_sigma[p * beauty_sigmas + c];
        }
        output->write_replaced_rows(row_begin, row_end, updated.data(), rebuilt, extra.data());
        return;
    }
    output->write_replaced_rows(row_begin, row_end, native, rebuilt, sigma);
}

void SequenceSink::write_rank_rows(int row_begin, int row_end, const float* ranks)
{
    if (m_rank_map_path.empty())
        return;
    if (!m_rank_map) {
        io::NewImageDescription image;
        image.width = m_reader.width();
        image.height = m_reader.height();
        image.channel_names = {"rank"};
        image.channel_types = {"float"};
        m_rank_map = std::make_unique<io::FrameOutput>(
            m_rank_map_path, image,
            std::vector<io::HeaderAttribute>{
                io::HeaderAttribute::of_text("modestack:command", command_line()),
                io::HeaderAttribute::of_text("modestack:rank_map",
                                             "modes used per pixel; a fraction blends the next mode in")});
    }
    m_rank_map->write_float_rows(row_begin, row_end, ranks);
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
