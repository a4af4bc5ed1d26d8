// The input side of every command that reads a frame sequence: opens every frame
// once, checks before any work that the frames agree (same data window, the
// selected channels present everywhere, not deep), then reads bands of
// scanlines of the selected channels as float, or of all channels in their
// native pixel types for bit-exact pass-through. Works on scanline and tiled
// files, single- or multi-part: a multi-part frame is read as one image of
// every part's channels, those of a part with bare channels (`R`, as Arnold,
// Karma and Nuke write a part per layer) in the layer the part's name makes
// (`<part name>.R`), those of a part whose channels all carry a layer as they
// are; its parts must share one data window. Never loads a whole frame unless
// asked for all its rows.
#pragma once

#include "io/exr_codec.h"
#include "io/layers.h"
#include "io/sequence.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace modestack::io {

namespace detail {
struct OpenFrame;
}

/// An opened, validated input sequence.
class SequenceReader {
public:
    /// Opens every file of `sequence` and selects the channels named by
    /// `layer_selectors` (see select_layers); `codec` decodes ZIP/ZIPS scanline
    /// frames. Throws Error naming the file on any unreadable, mismatched or
    /// unsupported frame.
    SequenceReader(const FrameSequence& sequence, const std::vector<std::string>& layer_selectors,
                   ExrCodec codec = ExrCodec::Libdeflate);
    ~SequenceReader();
    SequenceReader(const SequenceReader&) = delete;
    SequenceReader& operator=(const SequenceReader&) = delete;

    const FrameSequence& sequence() const { return m_sequence; }
    /// What decodes the frames' ZIP/ZIPS scanlines.
    ExrCodec exr_codec() const { return m_exr_codec; }
    int frame_count() const { return static_cast<int>(m_frames.size()); }
    int width() const { return m_width; }
    int height() const { return m_height; }
    /// The layers chosen for denoising and, flattened, their channels.
    const std::vector<SelectedLayer>& layers() const { return m_layers; }
    int selected_channel_count() const { return m_selected_channel_count; }
    /// Selected channel names in the order read_selected() interleaves them.
    std::vector<std::string> selected_channel_names() const;

    /// Reads rows [row_begin, row_end) of the data window (0 = its top row) of
    /// the selected channels of frame `frame_index` as float, interleaved
    /// [row][x][channel], into `destination`. Thread-safe across frames.
    void read_selected(int frame_index, int row_begin, int row_end, float* destination) const;
    /// Reads the same rows of all channels in their native pixel types,
    /// packed per pixel (as OIIO's TypeUnknown layout), resizing `destination`.
    void read_native(int frame_index, int row_begin, int row_end, std::vector<unsigned char>& destination) const;

    /// Converts the selected channels of `pixels` pixels of native rows (as
    /// read_native gives them for frame `frame_index`) to float, interleaved like
    /// read_selected's: the same values read_selected would read, without decoding
    /// the file again.
    void selected_from_native(int frame_index, const unsigned char* native, std::size_t pixels,
                              float* destination) const;
    /// Whether frame `frame_index` has channels that are not selected (an output
    /// copies them through from the native rows).
    bool has_unselected_channels(int frame_index) const;
    /// Bytes of one pixel of frame `frame_index` in native types, all channels.
    std::size_t native_pixel_bytes(int frame_index) const;
    /// Scanlines per compressed chunk of frame `frame_index` (OpenEXR: 1 for none,
    /// RLE and ZIPS, 16 for ZIP, 32 for PIZ, PXR24, B44 and DWAA, 256 for DWAB;
    /// the tile height of a tiled file): what an open file buffers at a time.
    int chunk_rows(int frame_index) const;
    /// Bytes the decoder holds for frame `frame_index`'s open file once its rows
    /// are read, beyond what opening it took: none when libdeflate decodes every
    /// part (its buffers are per thread), else OpenEXR's three chunks of scanlines.
    std::int64_t decoder_buffer_bytes(int frame_index) const;

    /// Every channel name of frame `frame_index`, in native row order.
    const std::vector<std::string>& channel_names(int frame_index) const;
    /// The selected channels of frame `frame_index` as indices into channel_names, in
    /// read_selected's order. Another reader of the same files has the same names and
    /// indices, so these also pick the selection out of that reader's native rows.
    const std::vector<int>& selected_channels(int frame_index) const;
    /// Converts channels `channels` (indices into channel_names) of `pixels`
    /// pixels of native rows to float, interleaved in that order.
    void channels_from_native(int frame_index, const unsigned char* native, std::size_t pixels,
                              const std::vector<int>& channels, float* destination) const;
    /// Stores float values, interleaved like channels_from_native's, into
    /// channels `channels` of native rows, each in its native type.
    void channels_to_native(int frame_index, unsigned char* native, std::size_t pixels,
                            const std::vector<int>& channels, const float* source) const;

    /// The opened frame, for io/'s writer.
    const detail::OpenFrame& frame(int frame_index) const { return *m_frames[frame_index]; }

private:
    FrameSequence m_sequence;
    ExrCodec m_exr_codec;
    std::vector<std::unique_ptr<detail::OpenFrame>> m_frames;
    std::vector<SelectedLayer> m_layers;
    int m_selected_channel_count = 0;
    int m_width = 0;
    int m_height = 0;
};

}  // namespace modestack::io
