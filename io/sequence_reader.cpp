#include "io/sequence_reader.h"

#include "core/common/error.h"
#include "io/detail/open_frame.h"
#include "io/detail/open_image.h"
#include "io/detail/zip_scanline_reader.h"
#include "io/frame_header.h"
#include "io/half_conversion.h"

#include <Imath/half.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace modestack::io {
namespace {

std::unique_ptr<detail::OpenFrame> open_frame(const std::string& file, int frame_number, ExrCodec codec)
{
    auto frame = std::make_unique<detail::OpenFrame>();
    frame->file = file;
    frame->frame_number = frame_number;
    frame->input = detail::open_checked_image(file, frame_number);
    frame->spec = frame->input->spec();
    if (frame->spec.deep)
        throw Error(ErrorKind::BadInput, "deep images are not supported", file, frame_number);
    if (frame->input->seek_subimage(1, 0))
        throw Error(ErrorKind::BadInput, "multi-part files are not supported (write a single-part EXR)", file,
                    frame_number);
    frame->input->seek_subimage(0, 0);
    if (frame->spec.width <= 0 || frame->spec.height <= 0)
        throw Error(ErrorKind::BadInput, "image has no pixels", file, frame_number);
    size_t offset = 0;
    for (int c = 0; c < frame->spec.nchannels; ++c) {
        frame->byte_offset.push_back(offset);
        offset += frame->spec.channelformat(c).size();
    }
    frame->native_pixel_bytes = offset;
    if (codec == ExrCodec::Libdeflate)
        frame->zip_layout = detail::zip_layout(*frame);
    return frame;
}

// Reads rows of channels [channel_begin, channel_end) of a scanline or tiled
// file in `type`, tightly packed.
void read_rows(const detail::OpenFrame& frame, int row_begin, int row_end, int channel_begin, int channel_end,
               OIIO::TypeDesc type, void* destination)
{
    const OIIO::ImageSpec& spec = frame.spec;
    if (frame.zip_layout && type == OIIO::TypeUnknown) {
        detail::read_zip_rows(frame, *frame.zip_layout, row_begin, row_end, channel_begin, channel_end,
                              static_cast<unsigned char*>(destination));
        return;
    }
    int y_begin = spec.y + row_begin, y_end = spec.y + row_end;
    bool ok;
    if (spec.tile_width == 0) {
        ok = frame.input->read_scanlines(0, 0, y_begin, y_end, spec.z, channel_begin, channel_end, type,
                                         destination);
    } else {
        // Tiles must be read whole: read the tile rows that cover the band, then copy.
        int tile_y0 = spec.y + (row_begin / spec.tile_height) * spec.tile_height;
        int tile_y1 = std::min(spec.y + spec.height,
                               spec.y + ((row_end + spec.tile_height - 1) / spec.tile_height) * spec.tile_height);
        size_t pixel_bytes = 0;
        for (int c = channel_begin; c < channel_end; ++c)
            pixel_bytes += type == OIIO::TypeUnknown ? spec.channelformat(c).size() : type.size();
        size_t row_bytes = pixel_bytes * spec.width;
        std::vector<unsigned char> tiles(row_bytes * (tile_y1 - tile_y0));
        ok = frame.input->read_tiles(0, 0, spec.x, spec.x + spec.width, tile_y0, tile_y1, spec.z, spec.z + 1,
                                     channel_begin, channel_end, type, tiles.data());
        if (ok)
            std::memcpy(destination, tiles.data() + (y_begin - tile_y0) * row_bytes, row_bytes * (row_end - row_begin));
    }
    if (!ok)
        throw Error(ErrorKind::BadInput,
                    fmt::format("cannot read rows {}-{} ({})", row_begin, row_end - 1, frame.input->geterror()),
                    frame.file, frame.frame_number);
}

}  // namespace

SequenceReader::SequenceReader(const FrameSequence& sequence, const std::vector<std::string>& layer_selectors,
                               ExrCodec codec)
    : m_sequence(sequence), m_exr_codec(codec)
{
    if (sequence.files.empty())
        throw bad_input(sequence.pattern, "no frames");
    for (size_t i = 0; i < sequence.files.size(); ++i)
        m_frames.push_back(open_frame(sequence.files[i], sequence.frames[i], codec));

    const detail::OpenFrame& first = *m_frames.front();
    m_width = first.spec.width;
    m_height = first.spec.height;
    m_layers = select_layers(first.spec.channelnames, layer_selectors, first.file);
    std::vector<std::string> names = selected_channel_names();
    m_selected_channel_count = static_cast<int>(names.size());

    for (auto& frame : m_frames) {
        const OIIO::ImageSpec& spec = frame->spec;
        if (spec.x != first.spec.x || spec.y != first.spec.y || spec.width != first.spec.width ||
            spec.height != first.spec.height)
            throw Error(ErrorKind::BadInput,
                        fmt::format("data window {} differs from {} in {}",
                                    describe_window(spec.x, spec.y, spec.width, spec.height),
                                    describe_window(first.spec.x, first.spec.y, first.spec.width, first.spec.height),
                                    first.file),
                        frame->file, frame->frame_number);
        for (const std::string& name : names) {
            int index = spec.channelindex(name);
            if (index < 0)
                throw Error(ErrorKind::BadInput,
                            fmt::format("channel '{}' not found (available: {})", name,
                                        fmt::join(spec.channelnames, ", ")),
                            frame->file, frame->frame_number);
            frame->selected.push_back(index);
        }
    }
}

SequenceReader::~SequenceReader() = default;

std::vector<std::string> SequenceReader::selected_channel_names() const
{
    std::vector<std::string> names;
    for (const auto& layer : m_layers)
        names.insert(names.end(), layer.channel_names.begin(), layer.channel_names.end());
    return names;
}

void SequenceReader::read_selected(int frame_index, int row_begin, int row_end, float* destination) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    const std::vector<int>& selected = frame.selected;
    int channel_begin = *std::min_element(selected.begin(), selected.end());
    int channel_end = *std::max_element(selected.begin(), selected.end()) + 1;
    bool contiguous = channel_end - channel_begin == static_cast<int>(selected.size());
    for (size_t i = 1; contiguous && i < selected.size(); ++i)
        contiguous = selected[i] == selected[i - 1] + 1;
    bool all_half = true;
    for (int channel : selected)
        all_half = all_half && frame.spec.channelformat(channel) == OIIO::TypeHalf;
    if (contiguous && all_half) {  // EXR's usual case: converted 8 values per instruction where the CPU can
        thread_local std::vector<std::uint16_t> halves;
        const size_t values = static_cast<size_t>(m_width) * (row_end - row_begin) * selected.size();
        halves.resize(values);
        read_rows(frame, row_begin, row_end, channel_begin, channel_end, OIIO::TypeUnknown, halves.data());
        halves_to_floats(halves.data(), destination, values);
        return;
    }
    if (contiguous) {
        read_rows(frame, row_begin, row_end, channel_begin, channel_end, OIIO::TypeFloat, destination);
        return;
    }
    // Selected channels are scattered: read the span that covers them, then pick.
    int span = channel_end - channel_begin;
    size_t pixels = static_cast<size_t>(m_width) * (row_end - row_begin);
    std::vector<float> covering(pixels * span);
    read_rows(frame, row_begin, row_end, channel_begin, channel_end, OIIO::TypeFloat, covering.data());
    size_t count = selected.size();
    for (size_t p = 0; p < pixels; ++p)
        for (size_t c = 0; c < count; ++c)
            destination[p * count + c] = covering[p * span + (selected[c] - channel_begin)];
}

void SequenceReader::read_native(int frame_index, int row_begin, int row_end,
                                 std::vector<unsigned char>& destination) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    destination.resize(frame.native_pixel_bytes * m_width * (row_end - row_begin));
    read_rows(frame, row_begin, row_end, 0, frame.spec.nchannels, OIIO::TypeUnknown, destination.data());
}

void SequenceReader::selected_from_native(int frame_index, const unsigned char* native, std::size_t pixels,
                                          float* destination) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    const std::size_t count = frame.selected.size();
    for (std::size_t k = 0; k < count; ++k) {
        const int channel = frame.selected[k];
        const OIIO::TypeDesc type = frame.spec.channelformat(channel);
        const unsigned char* source = native + frame.byte_offset[channel];
        const std::size_t stride = frame.native_pixel_bytes;
        if (type == OIIO::TypeHalf) {  // EXR's usual type: a table lookup, no dispatch per value
            for (std::size_t p = 0; p < pixels; ++p) {
                Imath::half value;
                std::memcpy(&value, source + p * stride, sizeof value);
                destination[p * count + k] = static_cast<float>(value);
            }
        } else if (type == OIIO::TypeFloat) {
            for (std::size_t p = 0; p < pixels; ++p)
                std::memcpy(destination + p * count + k, source + p * stride, sizeof(float));
        } else {
            for (std::size_t p = 0; p < pixels; ++p)
                OIIO::convert_pixel_values(type, source + p * stride, OIIO::TypeFloat, destination + p * count + k);
        }
    }
}

bool SequenceReader::has_unselected_channels(int frame_index) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    return static_cast<int>(frame.selected.size()) < frame.spec.nchannels;
}

int SequenceReader::chunk_rows(int frame_index) const
{
    const OIIO::ImageSpec& spec = m_frames.at(frame_index)->spec;
    if (spec.tile_height > 0)
        return spec.tile_height;
    const std::string compression = spec.get_string_attribute("compression", "none");
    if (compression == "zip")
        return 16;
    if (compression == "dwab")
        return 256;
    if (compression == "piz" || compression == "pxr24" || compression == "b44" || compression == "b44a" ||
        compression == "dwaa")
        return 32;
    return 1;  // none, rle, zips
}

std::size_t SequenceReader::native_pixel_bytes(int frame_index) const
{
    return m_frames.at(frame_index)->native_pixel_bytes;
}

std::size_t SequenceReader::selected_value_bytes(int frame_index) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    return frame.spec.channelformat(frame.selected.front()).size();
}

const std::vector<std::string>& SequenceReader::channel_names(int frame_index) const
{
    return m_frames.at(frame_index)->spec.channelnames;
}

void SequenceReader::channels_from_native(int frame_index, const unsigned char* native, std::size_t pixels,
                                          const std::vector<int>& channels, float* destination) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    for (std::size_t k = 0; k < channels.size(); ++k)
        for (std::size_t p = 0; p < pixels; ++p)
            OIIO::convert_pixel_values(frame.spec.channelformat(channels[k]),
                                       native + p * frame.native_pixel_bytes + frame.byte_offset[channels[k]],
                                       OIIO::TypeFloat, destination + p * channels.size() + k);
}

void SequenceReader::channels_to_native(int frame_index, unsigned char* native, std::size_t pixels,
                                        const std::vector<int>& channels, const float* source) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    for (std::size_t k = 0; k < channels.size(); ++k)
        for (std::size_t p = 0; p < pixels; ++p)
            OIIO::convert_pixel_values(
                OIIO::TypeFloat, source + p * channels.size() + k, frame.spec.channelformat(channels[k]),
                native + p * frame.native_pixel_bytes + frame.byte_offset[channels[k]]);
}

}  // namespace modestack::io
