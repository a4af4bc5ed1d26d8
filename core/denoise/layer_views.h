// The two ends of one layer's run when several layers run together
// (layer_runs.h): a LayerSource shows the layer's channels of a shared source,
// a LayerSink hands the layer's rebuilt rows to a LayerCombiner, which writes a
// frame's rows to the real sink once every layer has given them.
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace modestack::denoise {

/// Channels [first, first + count) of each pixel: one layer of the selected channels.
struct ChannelRange {
    int first = 0;
    int count = 0;
};

/// Copies channels `range` of `pixels` pixels of `channels` channels each into `to` (range.count a pixel).
void copy_channels(const float* from, int channels, ChannelRange range, std::int64_t pixels, float* to);

/// The layers of `shape`'s channels from each layer's channel count (in order,
/// adding up to shape.channels; an internal error otherwise).
std::vector<ChannelRange> layer_ranges(const std::vector<int>& layer_channels, const ShotShape& shape);

/// Rows of every channel decoded once for all layers: per frame, the rows of
/// the last read that had to decode, kept until a read asks for rows outside
/// them. Layers that read the same band in turn decode it once.
class SharedRows {
public:
    explicit SharedRows(FrameSource& source);
    const ShotShape& shape() const { return m_shape; }
    FrameSource& source() { return m_source; }
    /// Rows [row_begin, row_end) of frame `frame_index`, channels `range`, into
    /// `destination` ([row][x][channel of the range]). `pass_through` (may be
    /// null) receives the frame's other channels of these rows when the decode
    /// kept them and no earlier read took them: the first layer's reads hand
    /// them on to the sink.
    void read(int frame_index, int row_begin, int row_end, ChannelRange range, float* destination,
              PassThroughRows* pass_through);
    /// Lets the rows of frames [frame_begin, frame_end) go (every layer has read them).
    void release(int frame_begin, int frame_end);
    /// Decodes of frame rows so far (for tests: one per band and frame of a pass).
    std::int64_t decodes() const;

private:
    struct Frame {
        std::mutex mutex;
        int row_begin = 0, row_end = 0;
        std::vector<float> rows; // every channel, [row][x][channel]
        bool pass_through_kept = false;
        PassThroughRows pass_through;
        std::int64_t decodes = 0;
    };
    FrameSource& m_source;
    ShotShape m_shape;
    std::unique_ptr<Frame[]> m_frames;
};

/// One layer's channels of a SharedRows source.
class LayerSource : public FrameSource {
public:
    /// `first_layer`: this layer's reads take the pass-through rows for the sink.
    LayerSource(SharedRows& rows, ChannelRange range, bool first_layer);
    ShotShape shape() const override;
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override;
    std::int64_t band_bytes_per_row() const override;
    /// The variance has one channel per selected channel: the layer's are its
    /// range of them. Guides are the shot's, the same for every layer.
    int auxiliary_channels(Auxiliary kind) const override;
    void read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end,
                             float* destination) override;

private:
    SharedRows& m_rows;
    ChannelRange m_range;
    bool m_first_layer;
};

/// Gathers each layer's rows of a band into whole rows for the real sink.
class LayerCombiner {
public:
    LayerCombiner(FrameSink& sink, const ShotShape& shape, std::vector<ChannelRange> layers);
    /// Layer `layer` starts pass 2 with its N; the sink starts when every layer has.
    void begin(int layer, const RebuildStart& start);
    /// Layer `layer`'s rows of a frame; the last layer to give rows
    /// [row_begin, row_end) of a frame writes them. The first layer's
    /// pass-through rows and choices go on to the sink (they must stay valid
    /// until the last layer has given the same rows).
    void write_rows(int layer, int frame_index, int row_begin, int row_end, const float* rebuilt,
                    const float* sigma, const PassThroughRows* pass_through);
    void write_choice_rows(int layer, int frame_index, int row_begin, int row_end,
                           const std::uint8_t* chosen);
    FrameSink& sink() { return m_sink; }

private:
    struct Frame {
        std::mutex mutex;
        int row_begin = 0, row_end = 0;
        int given = 0; // layers that gave these rows
        std::vector<float> rebuilt, sigma;
        const PassThroughRows* pass_through = nullptr;
        std::vector<std::uint8_t> chosen; // the first layer's
    };
    FrameSink& m_sink;
    ShotShape m_shape;
    std::vector<ChannelRange> m_layers;
    std::vector<RebuildStart> m_starts;
    int m_started = 0;
    std::unique_ptr<Frame[]> m_frames;
};

/// One layer's end of a LayerCombiner.
class LayerSink : public FrameSink {
public:
    LayerSink(LayerCombiner& combiner, int layer) : m_combiner(combiner), m_layer(layer) {}
    void begin(const RebuildStart& start) override { m_combiner.begin(m_layer, start); }
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const PassThroughRows* pass_through) override
    {
        m_combiner.write_rows(m_layer, frame_index, row_begin, row_end, rebuilt, sigma, pass_through);
    }
    bool writes_frame(int frame_index) const override { return m_combiner.sink().writes_frame(frame_index); }
    void write_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen) override
    {
        m_combiner.write_choice_rows(m_layer, frame_index, row_begin, row_end, chosen);
    }

private:
    LayerCombiner& m_combiner;
    int m_layer;
};

} // namespace modestack::denoise
