// The two ends the denoise engine talks to, so that it knows nothing of files:
// a FrameSource hands out rows of the selected channels of every frame (and of
// auxiliary channels such as a variance layer, when the input has them), a
// FrameSink receives the rebuilt rows and their sigma. The app adapts io's
// SequenceReader and FrameOutput to them; tests use plain memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace modestack::denoise {

/// Size of a shot as the engine sees it.
struct ShotShape {
    int frames = 0;
    int width = 0;
    int height = 0;
    int channels = 0;  ///< selected channels per pixel (3 per RGB layer)
};

/// Per-pixel channels an input may hold next to the selected ones, which the
/// method can use but does not denoise.
enum class Auxiliary {
    Variance,  ///< variance of each selected channel's pixel mean (our renderer's `DiffIndVar`)
    Albedo,    ///< surface colour (`DiffCol`)
    Normal,    ///< shading normal (`Normal`)
    Depth,     ///< camera distance (`Depth`)
};

/// A frame's other channels (those an output copies unchanged) for some rows,
/// as the source decoded them beside the selected ones. Opaque to the engine:
/// pass 2 hands each band's on from its read to the write of the same rows, so
/// the sink decodes nothing twice and needs no way back into the source.
struct PassThroughRows {
    int row_begin = 0;
    int row_end = 0;
    std::vector<unsigned char> bytes; ///< empty: none kept (the sink decodes what it needs)

    /// The bytes of rows [begin, end) (`row_bytes` per row), or null unless all of them are kept.
    const unsigned char* rows(int begin, int end, std::size_t row_bytes) const
    {
        if (bytes.empty() || begin < row_begin || end > row_end)
            return nullptr;
        return bytes.data() + row_bytes * static_cast<std::size_t>(begin - row_begin);
    }
};

/// Rows of the selected channels of a shot.
class FrameSource {
public:
    virtual ~FrameSource() = default;
    virtual ShotShape shape() const = 0;
    /// Reads rows [row_begin, row_end) of frame `frame_index` as float,
    /// interleaved [row][x][channel]. With `pass_through` (pass 2's reads), the
    /// source may also leave there the frame's other channels of those rows, for
    /// the sink's write of the same rows. Called concurrently for different frames.
    virtual void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                           PassThroughRows* pass_through) = 0;
    /// Bytes of PassThroughRows per image row of a streamed band, all frames
    /// together, for the memory plan.
    virtual std::int64_t band_bytes_per_row() const { return 0; }
    /// Channels per pixel of `kind` (0: the input has none; Variance has one per
    /// selected channel).
    virtual int auxiliary_channels(Auxiliary kind) const
    {
        (void)kind;
        return 0;
    }
    /// Reads rows of `kind` like read_rows, [row][x][channel]; only for a kind
    /// with channels. Called concurrently for different frames.
    virtual void read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end, float* destination)
    {
        (void)kind, (void)frame_index, (void)row_begin, (void)row_end, (void)destination;
    }
    /// The variance of selected layer `layer` alone (the layers of
    /// Settings::layer_channels, in order): its channels, one per channel of
    /// the layer, or 0 when the input has none for it. A renderer may write a
    /// variance for some layers only (ours: DiffIndVar, no DiffDirVar), which
    /// the whole-selection Variance above cannot show.
    virtual int layer_variance_channels(int layer) const
    {
        (void)layer;
        return 0;
    }
    /// Reads rows of layer `layer`'s variance like read_rows; only for a layer with channels.
    virtual void read_layer_variance_rows(int layer, int frame_index, int row_begin, int row_end,
                                          float* destination)
    {
        (void)layer, (void)frame_index, (void)row_begin, (void)row_end, (void)destination;
    }
};

/// A FrameSource that hands on another's rows unchanged: decorators derive from
/// it and override only what they change, so a virtual added here is forwarded
/// by all of them.
class ForwardingSource : public FrameSource {
public:
    explicit ForwardingSource(FrameSource& inner) : m_inner(inner) {}
    ShotShape shape() const override { return m_inner.shape(); }
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override
    {
        m_inner.read_rows(frame_index, row_begin, row_end, destination, pass_through);
    }
    std::int64_t band_bytes_per_row() const override { return m_inner.band_bytes_per_row(); }
    int auxiliary_channels(Auxiliary kind) const override { return m_inner.auxiliary_channels(kind); }
    void read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end, float* destination) override
    {
        m_inner.read_auxiliary_rows(kind, frame_index, row_begin, row_end, destination);
    }
    int layer_variance_channels(int layer) const override { return m_inner.layer_variance_channels(layer); }
    void read_layer_variance_rows(int layer, int frame_index, int row_begin, int row_end,
                                  float* destination) override
    {
        m_inner.read_layer_variance_rows(layer, frame_index, row_begin, row_end, destination);
    }

protected:
    FrameSource& m_inner;
};

/// What is decided before the first rebuilt row: outputs record it.
struct RebuildStart {
    int kept_modes = 0;
    std::string rank_rule;
    std::string solver;
    /// Each layer's N when the layers have their own modes (Settings::layer_channels); empty: one N.
    std::vector<int> layer_modes;
};

/// Receives the result, band after band in increasing row order.
class FrameSink {
public:
    virtual ~FrameSink() = default;
    /// Called once, after the modes and N are known and before any write.
    virtual void begin(const RebuildStart& start) { (void)start; }
    /// Rows [row_begin, row_end) of frame `frame_index`: the rebuilt values and
    /// their standard error, both laid out like the source's rows, and what the
    /// source's read of these rows kept of the other channels (null or empty:
    /// nothing). Called concurrently for different frames, never for the same
    /// frame at once.
    virtual void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt,
                            const float* sigma, const PassThroughRows* pass_through) = 0;
    /// Rows of the spatial modes ps(x, y, j) (j < modes), [mode][row][x][channel].
    /// Only called when the sink asks for modes.
    virtual void write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes)
    {
        (void)row_begin, (void)row_end, (void)modes, (void)spatial_modes;
    }
    /// Whether write_mode_rows should be called.
    virtual bool wants_modes() const { return false; }
    /// Whether frame `frame_index` is written at all: a farm write task rebuilds
    /// only those frames (a whole run rebuilds every frame).
    virtual bool writes_frame(int frame_index) const
    {
        (void)frame_index;
        return true;
    }
    /// Rows of the per-pixel rank map (rank_map.h), one value per pixel. Only called
    /// when the run makes a rank map.
    virtual void write_rank_rows(int row_begin, int row_end, const float* ranks)
    {
        (void)row_begin, (void)row_end, (void)ranks;
    }
    /// Rows [row_begin, row_end) of frame `frame_index`: the Estimator
    /// (estimator_choice.h) each pixel's values were taken from, one per pixel.
    /// Called after write_rows of the same rows, only when the run chooses.
    virtual void write_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen)
    {
        (void)frame_index, (void)row_begin, (void)row_end, (void)chosen;
    }
};

/// A FrameSink that hands everything on to another unchanged (see ForwardingSource).
class ForwardingSink : public FrameSink {
public:
    explicit ForwardingSink(FrameSink& inner) : m_inner(inner) {}
    void begin(const RebuildStart& start) override { m_inner.begin(start); }
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const PassThroughRows* pass_through) override
    {
        m_inner.write_rows(frame_index, row_begin, row_end, rebuilt, sigma, pass_through);
    }
    void write_mode_rows(int row_begin, int row_end, int modes, const float* spatial_modes) override
    {
        m_inner.write_mode_rows(row_begin, row_end, modes, spatial_modes);
    }
    bool wants_modes() const override { return m_inner.wants_modes(); }
    bool writes_frame(int frame_index) const override { return m_inner.writes_frame(frame_index); }
    void write_rank_rows(int row_begin, int row_end, const float* ranks) override
    {
        m_inner.write_rank_rows(row_begin, row_end, ranks);
    }
    void write_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen) override
    {
        m_inner.write_choice_rows(frame_index, row_begin, row_end, chosen);
    }

protected:
    FrameSink& m_inner;
};

}  // namespace modestack::denoise
