#include "core/denoise/layer_views.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>

namespace modestack::denoise {

void copy_channels(const float* from, int channels, ChannelRange range, std::int64_t pixels, float* to)
{
    for (std::int64_t p = 0; p < pixels; ++p)
        std::copy_n(from + p * channels + range.first, range.count, to + p * range.count);
}

std::vector<ChannelRange> layer_ranges(const std::vector<int>& layer_channels, const ShotShape& shape)
{
    std::vector<ChannelRange> ranges;
    int first = 0;
    for (int count : layer_channels) {
        if (count <= 0)
            throw internal_error("a layer to denoise on its own modes has no channels");
        ranges.push_back({first, count});
        first += count;
    }
    if (first != shape.channels)
        throw internal_error(
            fmt::format("the layers' channels add up to {}, the shot has {}", first, shape.channels));
    return ranges;
}

SharedRows::SharedRows(FrameSource& source)
    : m_source(source), m_shape(source.shape()), m_frames(std::make_unique<Frame[]>(m_shape.frames))
{
}

void SharedRows::read(int frame_index, int row_begin, int row_end, ChannelRange range, float* destination,
                      PassThroughRows* pass_through)
{
    Frame& frame = m_frames[frame_index];
    const std::lock_guard<std::mutex> lock(frame.mutex);
    const bool held = frame.row_begin <= row_begin && row_end <= frame.row_end && !frame.rows.empty();
    if (!held || (pass_through && !frame.pass_through_kept)) {
        frame.rows.resize(static_cast<size_t>(row_end - row_begin) * m_shape.width * m_shape.channels);
        frame.pass_through = {};
        m_source.read_rows(frame_index, row_begin, row_end, frame.rows.data(),
                           pass_through ? &frame.pass_through : nullptr);
        frame.row_begin = row_begin, frame.row_end = row_end;
        frame.pass_through_kept = pass_through != nullptr;
        ++frame.decodes;
    }
    const std::int64_t row_pixels = m_shape.width;
    copy_channels(frame.rows.data() + (row_begin - frame.row_begin) * row_pixels * m_shape.channels,
                  m_shape.channels, range, row_pixels * (row_end - row_begin), destination);
    if (pass_through && frame.pass_through_kept) { // handed on once: the sink writes each row once
        *pass_through = std::move(frame.pass_through);
        frame.pass_through = {};
        frame.pass_through_kept = false;
    }
}

void SharedRows::release(int frame_begin, int frame_end)
{
    for (int t = frame_begin; t < frame_end; ++t) {
        Frame& frame = m_frames[t];
        const std::lock_guard<std::mutex> lock(frame.mutex);
        std::vector<float>().swap(frame.rows); // the memory itself (`rows = {}` would keep the capacity)
        frame.row_begin = frame.row_end = 0;
        frame.pass_through = {};
        frame.pass_through_kept = false;
    }
}

std::int64_t SharedRows::decodes() const
{
    std::int64_t total = 0;
    for (int t = 0; t < m_shape.frames; ++t)
        total += m_frames[t].decodes;
    return total;
}

LayerSource::LayerSource(SharedRows& rows, ChannelRange range, bool first_layer)
    : m_rows(rows), m_range(range), m_first_layer(first_layer)
{
}

ShotShape LayerSource::shape() const
{
    ShotShape shape = m_rows.shape();
    shape.channels = m_range.count;
    return shape;
}

void LayerSource::read_rows(int frame_index, int row_begin, int row_end, float* destination,
                            PassThroughRows* pass_through)
{
    m_rows.read(frame_index, row_begin, row_end, m_range, destination,
                m_first_layer ? pass_through : nullptr);
}

std::int64_t LayerSource::band_bytes_per_row() const
{
    return m_first_layer ? m_rows.source().band_bytes_per_row() : 0;
}

int LayerSource::auxiliary_channels(Auxiliary kind) const
{
    const int channels = m_rows.source().auxiliary_channels(kind);
    if (kind != Auxiliary::Variance)
        return channels;
    return channels == m_rows.shape().channels ? m_range.count : 0;
}

void LayerSource::read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end,
                                      float* destination)
{
    if (kind != Auxiliary::Variance) {
        m_rows.source().read_auxiliary_rows(kind, frame_index, row_begin, row_end, destination);
        return;
    }
    const ShotShape& shape = m_rows.shape();
    const std::int64_t pixels = static_cast<std::int64_t>(shape.width) * (row_end - row_begin);
    std::vector<float> all(static_cast<size_t>(pixels) * shape.channels);
    m_rows.source().read_auxiliary_rows(kind, frame_index, row_begin, row_end, all.data());
    copy_channels(all.data(), shape.channels, m_range, pixels, destination);
}

LayerCombiner::LayerCombiner(FrameSink& sink, const ShotShape& shape, std::vector<ChannelRange> layers)
    : m_sink(sink), m_shape(shape), m_layers(std::move(layers)), m_starts(m_layers.size()),
      m_frames(std::make_unique<Frame[]>(shape.frames))
{
}

void LayerCombiner::begin(int layer, const RebuildStart& start)
{
    m_starts[static_cast<size_t>(layer)] = start;
    if (++m_started < static_cast<int>(m_layers.size()))
        return;
    RebuildStart all = m_starts.front();
    for (const RebuildStart& each : m_starts)
        all.layer_modes.push_back(each.kept_modes);
    m_sink.begin(all);
}

void LayerCombiner::write_rows(int layer, int frame_index, int row_begin, int row_end, const float* rebuilt,
                               const float* sigma, const PassThroughRows* pass_through)
{
    Frame& frame = m_frames[frame_index];
    const std::lock_guard<std::mutex> lock(frame.mutex);
    const std::int64_t pixels = static_cast<std::int64_t>(m_shape.width) * (row_end - row_begin);
    if (frame.given == 0) {
        frame.row_begin = row_begin, frame.row_end = row_end;
        frame.rebuilt.resize(static_cast<size_t>(pixels) * m_shape.channels);
        frame.sigma.resize(frame.rebuilt.size());
        frame.pass_through = nullptr;
        frame.chosen.clear();
    } else if (frame.row_begin != row_begin || frame.row_end != row_end) {
        throw internal_error(fmt::format("layer {} wrote rows {}-{} of frame {} while the others wrote {}-{}",
                                         layer, row_begin, row_end, frame_index, frame.row_begin,
                                         frame.row_end));
    }
    const ChannelRange range = m_layers[static_cast<size_t>(layer)];
    for (std::int64_t p = 0; p < pixels; ++p) {
        std::copy_n(rebuilt + p * range.count, range.count,
                    frame.rebuilt.data() + p * m_shape.channels + range.first);
        std::copy_n(sigma + p * range.count, range.count,
                    frame.sigma.data() + p * m_shape.channels + range.first);
    }
    if (layer == 0)
        frame.pass_through = pass_through;
    if (++frame.given < static_cast<int>(m_layers.size()))
        return;
    frame.given = 0;
    m_sink.write_rows(frame_index, row_begin, row_end, frame.rebuilt.data(), frame.sigma.data(),
                      frame.pass_through);
    if (!frame.chosen.empty())
        m_sink.write_choice_rows(frame_index, row_begin, row_end, frame.chosen.data());
}

void LayerCombiner::write_choice_rows(int layer, int frame_index, int row_begin, int row_end,
                                      const std::uint8_t* chosen)
{
    if (layer != 0) // the sink's map shows one estimator a pixel: the first layer's
        return;
    Frame& frame = m_frames[frame_index];
    const std::lock_guard<std::mutex> lock(frame.mutex);
    frame.chosen.assign(chosen, chosen + static_cast<std::int64_t>(m_shape.width) * (row_end - row_begin));
}

} // namespace modestack::denoise
