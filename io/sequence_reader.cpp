#include "io/sequence_reader.h"

#include "core/common/error.h"
#include "io/detail/library_buffers.h"
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
#include <map>

namespace modestack::io {
namespace {

// Checks part `part` of `frame` (after part 0) against part 0, the frame the
// sequence is checked as: a multi-part frame is one image of several parts.
void check_part(const detail::OpenFrame& frame, const detail::OpenPart& part)
{
    const OIIO::ImageSpec& first = frame.parts.front().spec;
    const OIIO::ImageSpec& spec = part.spec;
    const std::string label = part.name.empty() ? fmt::format("part {}", part.subimage)
                                                : fmt::format("part {} '{}'", part.subimage, part.name);
    auto refuse = [&](const std::string& problem) {
        return Error(ErrorKind::BadInput, fmt::format("{} {}", label, problem), frame.file,
                     frame.frame_number);
    };
    if (spec.deep)
        throw refuse("is deep; deep images are not supported");
    if (spec.width <= 0 || spec.height <= 0)
        throw refuse("has no pixels");
    if (spec.x != first.x || spec.y != first.y || spec.width != first.width || spec.height != first.height)
        throw refuse(fmt::format("has data window {}, part 0 {}: the parts of a frame must share one window",
                                 describe_window(spec.x, spec.y, spec.width, spec.height),
                                 describe_window(first.x, first.y, first.width, first.height)));
}

// The frame's channels as one image: part 0's spec with every part's channels,
// named as part_channel_names says. Two parts naming one channel alike are refused.
OIIO::ImageSpec combined_spec(const detail::OpenFrame& frame)
{
    OIIO::ImageSpec spec = frame.parts.front().spec;
    spec.channelnames.clear();
    spec.channelformats.clear();
    std::map<std::string, const detail::OpenPart*> owners;
    for (const detail::OpenPart& part : frame.parts) {
        const std::vector<std::string> names = part_channel_names(part.name, part.spec.channelnames);
        for (int c = 0; c < part.spec.nchannels; ++c) {
            const std::string& name = names[c];
            if (auto [owner, added] = owners.emplace(name, &part); !added)
                throw Error(ErrorKind::BadInput,
                            fmt::format("channel '{}' is in part {} and part {}: a layer must be in one part",
                                        name, owner->second->subimage, part.subimage),
                            frame.file, frame.frame_number);
            spec.channelnames.push_back(name);
            spec.channelformats.push_back(part.spec.channelformat(c));
        }
    }
    spec.nchannels = static_cast<int>(spec.channelnames.size());
    spec.format = spec.channelformats.front();
    // The parts' own bookkeeping is not the frame's (a --single-part output must not claim a part).
    for (const char* name : {"oiio:subimagename", "oiio:subimages", "name", "type", "openexr:chunkCount"})
        spec.erase_attribute(name);
    return spec;
}

std::unique_ptr<detail::OpenFrame> open_frame(const std::string& file, int frame_number, ExrCodec codec)
{
    auto frame = std::make_unique<detail::OpenFrame>();
    frame->file = file;
    frame->frame_number = frame_number;
    frame->input = detail::open_checked_image(file, frame_number);
    for (int subimage = 0; frame->input->seek_subimage(subimage, 0); ++subimage) {
        detail::OpenPart part;
        part.subimage = subimage;
        part.spec = frame->input->spec();
        // A single-part file is presented as it is, whatever name it carries.
        part.name = part.spec.get_string_attribute("oiio:subimagename");
        frame->parts.push_back(std::move(part));
    }
    frame->input->seek_subimage(0, 0);
    if (frame->parts.empty())
        throw Error(ErrorKind::BadInput, "image has no parts", file, frame_number);
    if (frame->parts.front().spec.deep)
        throw Error(ErrorKind::BadInput, "deep images are not supported", file, frame_number);
    if (frame->parts.front().spec.width <= 0 || frame->parts.front().spec.height <= 0)
        throw Error(ErrorKind::BadInput, "image has no pixels", file, frame_number);
    if (frame->parts.size() == 1) {
        frame->parts.front().name.clear();
        frame->spec = frame->parts.front().spec;
    } else {
        for (size_t p = 1; p < frame->parts.size(); ++p)
            check_part(*frame, frame->parts[p]);
        frame->spec = combined_spec(*frame);
    }
    size_t offset = 0;
    for (int c = 0; c < frame->spec.nchannels; ++c) {
        frame->byte_offset.push_back(offset);
        offset += frame->spec.channelformat(c).size();
    }
    frame->native_pixel_bytes = offset;
    int first_channel = 0;
    for (detail::OpenPart& part : frame->parts) {
        part.first_channel = first_channel;
        part.byte_offset = frame->byte_offset[first_channel];
        first_channel += part.spec.nchannels;
        part.native_pixel_bytes =
            (first_channel < frame->spec.nchannels ? frame->byte_offset[first_channel] : offset) -
            part.byte_offset;
        if (codec == ExrCodec::Libdeflate)
            part.zip_layout = detail::zip_layout(*frame, part);
    }
    return frame;
}

// Converts one channel of `pixels` native pixels (`stride` bytes apart, the
// first value at `source`) to float, into every `count`-th float of
// `destination`: the values OIIO gives when asked for floats.
void native_channel_to_floats(OIIO::TypeDesc type, const unsigned char* source, size_t stride, size_t pixels,
                              float* destination, size_t count)
{
    if (type == OIIO::TypeHalf) { // EXR's usual type: a table lookup, no dispatch per value
        for (size_t p = 0; p < pixels; ++p) {
            Imath::half value;
            std::memcpy(&value, source + p * stride, sizeof value);
            destination[p * count] = static_cast<float>(value);
        }
    } else if (type == OIIO::TypeFloat) {
        for (size_t p = 0; p < pixels; ++p)
            std::memcpy(destination + p * count, source + p * stride, sizeof(float));
    } else {
        for (size_t p = 0; p < pixels; ++p)
            OIIO::convert_pixel_values(type, source + p * stride, OIIO::TypeFloat, destination + p * count);
    }
}

// Reads rows of channels [channel_begin, channel_end) of one scanline or tiled
// part (its own channel indices) in `type`, tightly packed.
void read_part_rows(const detail::OpenFrame& frame, const detail::OpenPart& part, int row_begin, int row_end,
                    int channel_begin, int channel_end, OIIO::TypeDesc type, void* destination)
{
    const OIIO::ImageSpec& spec = part.spec;
    if (part.zip_layout && type == OIIO::TypeUnknown) {
        detail::read_zip_rows(frame, *part.zip_layout, row_begin, row_end, channel_begin, channel_end,
                              static_cast<unsigned char*>(destination));
        return;
    }
    int y_begin = spec.y + row_begin, y_end = spec.y + row_end;
    bool ok;
    if (spec.tile_width == 0) {
        ok = frame.input->read_scanlines(part.subimage, 0, y_begin, y_end, spec.z, channel_begin, channel_end,
                                         type, destination);
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
        ok = frame.input->read_tiles(part.subimage, 0, spec.x, spec.x + spec.width, tile_y0, tile_y1, spec.z,
                                     spec.z + 1, channel_begin, channel_end, type, tiles.data());
        if (ok)
            std::memcpy(destination, tiles.data() + (y_begin - tile_y0) * row_bytes, row_bytes * (row_end - row_begin));
    }
    if (!ok)
        throw Error(ErrorKind::BadInput,
                    fmt::format("cannot read rows {}-{} ({})", row_begin, row_end - 1, frame.input->geterror()),
                    frame.file, frame.frame_number);
}

// Reads rows of channels [channel_begin, channel_end) of the frame (every
// part's, in part order) in `type`, tightly packed per pixel.
void read_rows(const detail::OpenFrame& frame, int row_begin, int row_end, int channel_begin, int channel_end,
               OIIO::TypeDesc type, void* destination)
{
    if (!frame.multipart()) {
        read_part_rows(frame, frame.parts.front(), row_begin, row_end, channel_begin, channel_end, type,
                       destination);
        return;
    }
    auto value_bytes = [&](int channel) {
        return type == OIIO::TypeUnknown ? frame.spec.channelformat(channel).size() : type.size();
    };
    size_t pixel_bytes = 0;
    for (int c = channel_begin; c < channel_end; ++c)
        pixel_bytes += value_bytes(c);
    const size_t pixels = static_cast<size_t>(frame.spec.width) * (row_end - row_begin);
    auto* out = static_cast<unsigned char*>(destination);
    thread_local std::vector<unsigned char> part_rows;
    size_t out_offset = 0; // of the part's first read channel in an output pixel
    for (const detail::OpenPart& part : frame.parts) {
        const int begin = std::max(channel_begin, part.first_channel);
        const int end = std::min(channel_end, part.first_channel + part.spec.nchannels);
        if (begin >= end)
            continue;
        size_t part_pixel_bytes = 0;
        for (int c = begin; c < end; ++c)
            part_pixel_bytes += value_bytes(c);
        part_rows.resize(pixels * part_pixel_bytes);
        read_part_rows(frame, part, row_begin, row_end, begin - part.first_channel, end - part.first_channel,
                       type, part_rows.data());
        for (size_t p = 0; p < pixels; ++p)
            std::memcpy(out + p * pixel_bytes + out_offset, part_rows.data() + p * part_pixel_bytes,
                        part_pixel_bytes);
        out_offset += part_pixel_bytes;
    }
}

// Scanlines per compressed chunk of a part (see chunk_rows()).
int part_chunk_rows(const OIIO::ImageSpec& spec)
{
    if (spec.tile_height > 0)
        return spec.tile_height;
    return detail::scanlines_per_chunk(spec.get_string_attribute("compression", "none"));
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
    // Anything else (float or mixed types, scattered channels): the native values
    // of the span that covers the selection, converted channel by channel. Read
    // natively, a ZIP part goes through libdeflate; asked for floats, OIIO would
    // decode it again through OpenEXR's zlib.
    thread_local std::vector<unsigned char> span;
    const size_t pixels = static_cast<size_t>(m_width) * (row_end - row_begin);
    const size_t span_begin = frame.byte_offset[channel_begin];
    const size_t span_bytes =
        (channel_end < frame.spec.nchannels ? frame.byte_offset[channel_end] : frame.native_pixel_bytes) -
        span_begin;
    span.resize(pixels * span_bytes);
    read_rows(frame, row_begin, row_end, channel_begin, channel_end, OIIO::TypeUnknown, span.data());
    for (size_t k = 0; k < selected.size(); ++k)
        native_channel_to_floats(frame.spec.channelformat(selected[k]),
                                 span.data() + (frame.byte_offset[selected[k]] - span_begin), span_bytes,
                                 pixels, destination + k, selected.size());
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
    for (std::size_t k = 0; k < count; ++k)
        native_channel_to_floats(frame.spec.channelformat(frame.selected[k]),
                                 native + frame.byte_offset[frame.selected[k]], frame.native_pixel_bytes,
                                 pixels, destination + k, count);
}

bool SequenceReader::has_unselected_channels(int frame_index) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    return static_cast<int>(frame.selected.size()) < frame.spec.nchannels;
}

int SequenceReader::chunk_rows(int frame_index) const
{
    int rows = 1;
    for (const detail::OpenPart& part : m_frames.at(frame_index)->parts)
        rows = std::max(rows, part_chunk_rows(part.spec));
    return rows;
}

std::int64_t SequenceReader::decoder_buffer_bytes(int frame_index) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    const bool libdeflate =
        std::all_of(frame.parts.begin(), frame.parts.end(),
                    [](const detail::OpenPart& part) { return part.zip_layout != nullptr; });
    return libdeflate ? 0
                      : detail::openexr_file_buffer_bytes(m_width, frame.native_pixel_bytes,
                                                          chunk_rows(frame_index));
}

std::size_t SequenceReader::native_pixel_bytes(int frame_index) const
{
    return m_frames.at(frame_index)->native_pixel_bytes;
}

const std::vector<std::string>& SequenceReader::channel_names(int frame_index) const
{
    return m_frames.at(frame_index)->spec.channelnames;
}

const std::vector<int>& SequenceReader::selected_channels(int frame_index) const
{
    return m_frames.at(frame_index)->selected;
}

void SequenceReader::channels_from_native(int frame_index, const unsigned char* native, std::size_t pixels,
                                          const std::vector<int>& channels, float* destination) const
{
    const detail::OpenFrame& frame = *m_frames.at(frame_index);
    for (std::size_t k = 0; k < channels.size(); ++k)
        native_channel_to_floats(frame.spec.channelformat(channels[k]),
                                 native + frame.byte_offset[channels[k]], frame.native_pixel_bytes, pixels,
                                 destination + k, channels.size());
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
