#include "io/frame_output.h"

#include "core/common/error.h"
#include "io/detail/library_buffers.h"
#include "io/detail/multipart_writer.h"
#include "io/detail/open_frame.h"
#include "io/detail/output_layout.h"
#include "io/detail/zip_scanline_writer.h"
#include "io/half_conversion.h"
#include "io/layers.h"
#include "io/sequence_reader.h"
#include "io/temporary_file.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <set>
#include <system_error>
#include <utility>
#include <unistd.h>

namespace modestack::io {
namespace {

namespace stdfs = std::filesystem;

// Stores a float in a channel of the given pixel type.
void store_value(float value, OIIO::TypeDesc type, unsigned char* destination)
{
    if (type == OIIO::TypeDesc::HALF) {
        Imath::half h(value);
        std::memcpy(destination, &h, sizeof h);
    } else if (type == OIIO::TypeDesc::FLOAT) {
        std::memcpy(destination, &value, sizeof value);
    } else {
        OIIO::convert_pixel_values(OIIO::TypeFloat, &value, type, destination, 1);
    }
}

void add_attributes(OIIO::ImageSpec& spec, const std::vector<HeaderAttribute>& attributes)
{
    for (const auto& attribute : attributes) {
        switch (attribute.kind) {
        case HeaderAttribute::Kind::Text: spec.attribute(attribute.name, attribute.text); break;
        case HeaderAttribute::Kind::Integer: spec.attribute(attribute.name, static_cast<int>(attribute.integer)); break;
        case HeaderAttribute::Kind::Real: spec.attribute(attribute.name, static_cast<float>(attribute.real)); break;
        }
    }
}

// The temporary name an output is written under; a killed run's leftovers in
// its directory are removed first.
std::string claim_temporary_path(const std::string& path)
{
    remove_stale_temporaries(path);
    return temporary_path_for(path);
}

OIIO::TypeDesc type_written(WrittenType written, OIIO::TypeDesc as_input)
{
    switch (written) {
    case WrittenType::Half:
        return OIIO::TypeDesc::HALF;
    case WrittenType::Float:
        return OIIO::TypeDesc::FLOAT;
    case WrittenType::AsInput:
        break;
    }
    return as_input;
}

// The channels of a copy of `source` (see output_layout.h) and each output part's compression.
detail::OutputLayout layout_of(const detail::OpenFrame& source,
                               const std::vector<std::string>& extra_channels, const OutputFormat& format,
                               bool multipart_output)
{
    const OIIO::ImageSpec& spec = source.spec;
    std::vector<bool> replaced(static_cast<size_t>(spec.nchannels), false);
    for (int channel : source.selected)
        replaced[static_cast<size_t>(channel)] = true;
    const std::set<std::string> kept_layers(format.kept_layers.begin(), format.kept_layers.end());
    // An input that is itself a denoise output has sigma channels already: the
    // new ones replace them, never a second set under the same names.
    const std::set<std::string> added(extra_channels.begin(), extra_channels.end());
    detail::OutputLayout layout;
    for (int c = 0; c < spec.nchannels; ++c) {
        const std::string& name = spec.channelnames[c];
        if (!replaced[c] && added.count(name))
            continue;
        std::string layer, component;
        split_channel_name(name, layer, component);
        // The unnamed layer is the bare R, G, B, A (a bare Z is a layer of its own, layers.h).
        const bool in_kept_layer =
            kept_layers.count(layer) &&
            (!layer.empty() || component == "R" || component == "G" || component == "B" || component == "A");
        if (format.only_written && !replaced[c] && !in_kept_layer)
            continue;
        // Untouched channels keep their type always; --data-type is for what is written anew.
        const OIIO::TypeDesc type =
            replaced[c] ? type_written(format.written_type, spec.channelformat(c)) : spec.channelformat(c);
        layout.channels.push_back({name, type, layout.pixel_bytes, c});
        layout.pixel_bytes += type.size();
    }
    const OIIO::TypeDesc extra_type =
        type_written(format.written_type, spec.channelformat(source.selected.front()));
    for (const std::string& name : extra_channels) {
        layout.channels.push_back({name, extra_type, layout.pixel_bytes, -1});
        layout.pixel_bytes += extra_type.size();
    }
    if (multipart_output)
        for (const detail::OpenPart& part : source.parts)
            layout.compressions.push_back(
                output_compression(format.compression, part.spec.get_string_attribute("compression")));
    else
        layout.compressions.push_back(
            output_compression(format.compression, spec.get_string_attribute("compression")));
    return layout;
}

// Whether libdeflate writes the copy (zip_scanline_writer.h): a single-part ZIP or
// ZIPS output with the libdeflate codec. Anything else goes through OpenEXR's
// library (a multi-part copy) or OpenImageIO.
bool written_with_libdeflate(const detail::OutputLayout& layout, ExrCodec codec, bool multipart_output)
{
    const std::string method = split_compression(layout.compressions.front()).method;
    return !multipart_output && codec == ExrCodec::Libdeflate && (method == "zip" || method == "zips");
}

// The output channel that copies or replaces input channel `channel`, or -1.
int output_index_of(const detail::OutputLayout& layout, int channel)
{
    for (size_t k = 0; k < layout.channels.size(); ++k)
        if (layout.channels[k].input_channel == channel)
            return static_cast<int>(k);
    return -1;
}

// OpenImageIO's spec of a copy of `source` laid out as `layout` (one part).
OIIO::ImageSpec spec_of(const detail::OpenFrame& source, const detail::OutputLayout& layout,
                        const std::vector<HeaderAttribute>& attributes)
{
    OIIO::ImageSpec spec = source.spec;
    spec.channelnames.clear();
    spec.channelformats.clear();
    for (const detail::OutputChannel& channel : layout.channels) {
        spec.channelnames.push_back(channel.name);
        spec.channelformats.push_back(channel.type);
    }
    spec.nchannels = static_cast<int>(spec.channelnames.size());
    spec.alpha_channel =
        source.spec.alpha_channel < 0 ? -1 : output_index_of(layout, source.spec.alpha_channel);
    spec.z_channel = source.spec.z_channel < 0 ? -1 : output_index_of(layout, source.spec.z_channel);
    spec.tile_width = spec.tile_height = spec.tile_depth = 0;
    spec.erase_attribute("openexr:lineOrder");
    // The input's DWA level is no part of the output's compression (a level asked for is in its name).
    spec.erase_attribute("openexr:dwaCompressionLevel");
    spec.erase_attribute("dwaCompressionLevel");
    spec.attribute("compression", layout.compressions.front());
    add_attributes(spec, attributes);
    return spec;
}

}  // namespace

HeaderAttribute HeaderAttribute::of_text(std::string name, std::string value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.text = std::move(value);
    return attribute;
}
HeaderAttribute HeaderAttribute::of_integer(std::string name, long long value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.kind = Kind::Integer;
    attribute.integer = value;
    return attribute;
}
HeaderAttribute HeaderAttribute::of_real(std::string name, double value)
{
    HeaderAttribute attribute;
    attribute.name = std::move(name);
    attribute.kind = Kind::Real;
    attribute.real = value;
    return attribute;
}

// Where in an output pixel a written value goes, and as what.
struct ValuePlace {
    size_t byte_offset = 0;
    OIIO::TypeDesc type;
};

// Bytes copied unchanged from an input pixel into an output pixel.
struct CopiedBytes {
    size_t input_offset = 0, output_offset = 0, bytes = 0;
};

struct FrameOutput::State {
    std::unique_ptr<detail::ZipScanlineWriter> zip_writer;  ///< a ZIP/ZIPS copy, written with libdeflate
    std::unique_ptr<detail::MultiPartWriter> multipart_writer; ///< a multi-part copy in the input's parts
    std::unique_ptr<OIIO::ImageOutput> output;              ///< every other output
    OIIO::ImageSpec spec;
    const detail::OpenFrame* source = nullptr; ///< the copied input frame, if any
    size_t output_pixel_bytes = 0;
    std::vector<ValuePlace> replaced_places, extra_places;  ///< of each replaced / extra value of a pixel
    /// The output pixel starts with the input pixel as it is (every channel kept, in its type):
    /// copied whole. Otherwise `copied` lists the kept channels' bytes.
    bool input_pixel_whole = false;
    std::vector<CopiedBytes> copied;
    bool copies_input = false;     ///< some kept channel is passed through (not replaced)
    bool all_places_half = false;  ///< every written value is a half: converted a row at a time
};

FrameOutput::FrameOutput(const std::string& path, const SequenceReader& reader, int frame_index,
                         const std::vector<std::string>& extra_channels,
                         const std::vector<HeaderAttribute>& attributes, ExrCodec codec, PartLayout parts,
                         const OutputFormat& format)
    : m_path(path), m_temporary_path(claim_temporary_path(path)), m_state(std::make_unique<State>())
{
    const detail::OpenFrame& source = reader.frame(frame_index);
    m_state->source = &source;
    const bool multipart_output = source.multipart() && parts == PartLayout::AsInput;
    const detail::OutputLayout layout = layout_of(source, extra_channels, format, multipart_output);
    m_state->output_pixel_bytes = layout.pixel_bytes;
    std::vector<int> output_of(static_cast<size_t>(source.spec.nchannels), -1); // by input channel
    for (size_t k = 0; k < layout.channels.size(); ++k) {
        const detail::OutputChannel& channel = layout.channels[k];
        if (channel.input_channel < 0)
            m_state->extra_places.push_back({channel.offset, channel.type});
        else
            output_of[static_cast<size_t>(channel.input_channel)] = static_cast<int>(k);
    }
    for (int channel : source.selected)
        m_state->replaced_places.push_back(
            {layout.channels[output_of[channel]].offset, layout.channels[output_of[channel]].type});
    m_state->input_pixel_whole = true;
    std::vector<bool> replaced(output_of.size(), false);
    for (int channel : source.selected)
        replaced[static_cast<size_t>(channel)] = true;
    for (int c = 0; c < source.spec.nchannels; ++c) {
        const int k = output_of[static_cast<size_t>(c)];
        if (k < 0 || layout.channels[k].offset != source.byte_offset[c] ||
            layout.channels[k].type != source.spec.channelformat(c))
            m_state->input_pixel_whole = false;
        if (k < 0 || replaced[static_cast<size_t>(c)])
            continue;
        m_state->copies_input = true;
        const size_t bytes = layout.channels[k].type.size();
        std::vector<CopiedBytes>& copied = m_state->copied;
        if (!copied.empty() && copied.back().input_offset + copied.back().bytes == source.byte_offset[c] &&
            copied.back().output_offset + copied.back().bytes == layout.channels[k].offset)
            copied.back().bytes += bytes; // one run of neighbouring channels, one copy
        else
            copied.push_back({source.byte_offset[c], layout.channels[k].offset, bytes});
    }
    m_state->all_places_half = true;
    for (const auto* places : {&m_state->replaced_places, &m_state->extra_places})
        for (const ValuePlace& place : *places)
            m_state->all_places_half = m_state->all_places_half && place.type == OIIO::TypeDesc::HALF;
    m_state->spec = spec_of(source, layout, attributes);
    if (multipart_output) {
        m_state->multipart_writer =
            std::make_unique<detail::MultiPartWriter>(m_temporary_path, m_path, source, layout, attributes);
        return;
    }
    if (written_with_libdeflate(layout, codec, multipart_output))
        m_state->zip_writer =
            detail::ZipScanlineWriter::open(m_temporary_path, m_path, source, layout, attributes);
    if (!m_state->zip_writer) {
        const OIIO::ImageSpec spec = m_state->spec;
        open(&spec);
    }
}

std::int64_t copy_buffer_bytes(const SequenceReader& reader, int frame_index,
                               const std::vector<std::string>& extra_channels, ExrCodec codec,
                               PartLayout parts, const OutputFormat& format)
{
    const detail::OpenFrame& source = reader.frame(frame_index);
    const bool multipart_output = source.multipart() && parts == PartLayout::AsInput;
    const detail::OutputLayout layout = layout_of(source, extra_channels, format, multipart_output);
    // The writer takes single-part ZIP/ZIPS scanline inputs only (zip_scanline_writer.h):
    // those the reader decodes with libdeflate. It holds the chunk being filled.
    if (written_with_libdeflate(layout, codec, multipart_output) && !source.multipart() &&
        source.parts.front().zip_layout)
        return static_cast<std::int64_t>(layout.pixel_bytes) * reader.width() *
               detail::scanlines_per_chunk(split_compression(layout.compressions.front()).method);
    return detail::openexr_file_buffer_bytes(reader.width(), layout.pixel_bytes,
                                             reader.chunk_rows(frame_index));
}

FrameOutput::FrameOutput(const std::string& path, const NewImageDescription& image,
                         const std::vector<HeaderAttribute>& attributes)
    : m_path(path), m_temporary_path(claim_temporary_path(path)), m_state(std::make_unique<State>())
{
    OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.channel_names.size()), OIIO::TypeFloat);
    spec.channelnames = image.channel_names;
    spec.channelformats.clear();
    for (const std::string& type : image.channel_types)
        spec.channelformats.push_back(OIIO::TypeDesc(type));
    spec.alpha_channel = -1;
    for (size_t c = 0; c < image.channel_names.size(); ++c)
        if (image.channel_names[c] == "A" || (image.channel_names[c].size() > 2 &&
                                              image.channel_names[c].compare(image.channel_names[c].size() - 2, 2, ".A") == 0)) {
            spec.alpha_channel = static_cast<int>(c);
            break;
        }
    spec.attribute("compression", image.compression);
    add_attributes(spec, attributes);
    open(&spec);
}

void FrameOutput::open(const void* spec_pointer)
{
    const OIIO::ImageSpec& spec = *static_cast<const OIIO::ImageSpec*>(spec_pointer);
    m_state->spec = spec;
    m_state->output = OIIO::ImageOutput::create("openexr");
    if (!m_state->output)
        throw internal_error("OpenImageIO has no OpenEXR writer");
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->open(m_temporary_path, m_state->spec))
        fail("cannot create output");
}

FrameOutput::~FrameOutput()
{
    if (m_committed)
        return;
    if (m_state && m_state->output)
        m_state->output->close();
    if (m_state) { // closes the file before it is removed
        m_state->zip_writer.reset();
        m_state->multipart_writer.reset();
    }
    std::error_code ignored;
    if (!m_temporary_path.empty())
        stdfs::remove(m_temporary_path, ignored);
}

void FrameOutput::fail(const std::string& what)
{
    const int system_error = errno;  // OpenEXR's message ("File output failed.") does not say why
    std::string reason = m_state->output ? m_state->output->geterror() : std::string();
    if (system_error != 0) {
        const std::string system_reason = std::strerror(system_error);
        reason = reason.empty() ? system_reason : fmt::format("{}: {}", reason, system_reason);
    }
    throw bad_input(m_path, reason.empty() ? what : fmt::format("{} ({})", what, reason));
}

void FrameOutput::write_replaced_rows(int row_begin, int row_end, const std::vector<unsigned char>& input_native,
                                      const float* replaced, const float* extra)
{
    const detail::OpenFrame& source = *m_state->source;
    size_t pixels = static_cast<size_t>(source.spec.width) * (row_end - row_begin);
    if (needs_input_rows() && input_native.size() != pixels * source.native_pixel_bytes)
        throw internal_error("native row buffer has the wrong size");
    write_replaced_rows(row_begin, row_end, input_native.empty() ? nullptr : input_native.data(), replaced, extra);
}

void FrameOutput::write_replaced_rows(int row_begin, int row_end, const unsigned char* input_native,
                                      const float* replaced, const float* extra)
{
    const detail::OpenFrame& source = *m_state->source;
    const OIIO::ImageSpec& input_spec = source.spec;
    size_t pixels = static_cast<size_t>(input_spec.width) * (row_end - row_begin);
    size_t in_bytes = source.native_pixel_bytes, out_bytes = m_state->output_pixel_bytes;
    // Without pass-through channels every input byte is overwritten: no input rows needed.
    const bool copy_input = needs_input_rows();
    if (copy_input && !input_native)
        throw internal_error("native rows missing for a frame with pass-through channels");
    // Per thread, not per output: a shot has hundreds of outputs open at once.
    thread_local std::vector<unsigned char> scratch;
    scratch.resize(pixels * out_bytes);
    unsigned char* out = scratch.data();
    if (copy_input && m_state->input_pixel_whole)
        for (size_t p = 0; p < pixels; ++p)
            std::memcpy(out + p * out_bytes, input_native + p * in_bytes, in_bytes);
    else if (copy_input)
        for (size_t p = 0; p < pixels; ++p)
            for (const CopiedBytes& run : m_state->copied)
                std::memcpy(out + p * out_bytes + run.output_offset,
                            input_native + p * in_bytes + run.input_offset, run.bytes);
    if (m_state->all_places_half)
        place_halves(pixels, replaced, extra, out);
    else
        place_values(pixels, replaced, extra, out);
    if (m_state->zip_writer) {
        m_state->zip_writer->write_rows(row_begin, row_end, out);
        return;
    }
    if (m_state->multipart_writer) {
        m_state->multipart_writer->write_rows(row_begin, row_end, out);
        return;
    }
    const OIIO::ImageSpec& spec = m_state->spec;
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->write_scanlines(spec.y + row_begin, spec.y + row_end, spec.z, OIIO::TypeUnknown, out))
        fail(fmt::format("cannot write rows {}-{}", row_begin, row_end - 1));
}

// Half outputs (the common case) are converted in batches, a row at a time, then
// placed: the batch conversion runs 8 values per instruction where the CPU can.
void FrameOutput::place_halves(size_t pixels, const float* replaced, const float* extra, unsigned char* out) const
{
    const size_t out_bytes = m_state->output_pixel_bytes, width = static_cast<size_t>(m_state->spec.width);
    thread_local std::vector<std::uint16_t> halves;
    for (const auto& [values, places] : {std::pair{replaced, &m_state->replaced_places},
                                         std::pair{extra, &m_state->extra_places}}) {
        const size_t count = places->size();
        if (count == 0)
            continue;
        halves.resize(width * count);
        for (size_t row_start = 0; row_start < pixels; row_start += width) {
            const size_t row_pixels = std::min(width, pixels - row_start);
            floats_to_halves(values + row_start * count, halves.data(), row_pixels * count);
            for (size_t p = 0; p < row_pixels; ++p) {
                unsigned char* pixel = out + (row_start + p) * out_bytes;
                for (size_t k = 0; k < count; ++k)
                    std::memcpy(pixel + (*places)[k].byte_offset, &halves[p * count + k], sizeof(std::uint16_t));
            }
        }
    }
}

void FrameOutput::place_values(size_t pixels, const float* replaced, const float* extra, unsigned char* out) const
{
    const size_t out_bytes = m_state->output_pixel_bytes;
    const std::vector<ValuePlace>& replaced_places = m_state->replaced_places;
    const std::vector<ValuePlace>& extra_places = m_state->extra_places;
    for (size_t p = 0; p < pixels; ++p) {
        unsigned char* pixel = out + p * out_bytes;
        for (size_t k = 0; k < replaced_places.size(); ++k)
            store_value(replaced[p * replaced_places.size() + k], replaced_places[k].type,
                        pixel + replaced_places[k].byte_offset);
        for (size_t k = 0; k < extra_places.size(); ++k)
            store_value(extra[p * extra_places.size() + k], extra_places[k].type, pixel + extra_places[k].byte_offset);
    }
}

bool FrameOutput::needs_input_rows() const
{
    return m_state->copies_input;
}

void FrameOutput::write_float_rows(int row_begin, int row_end, const float* pixels)
{
    const OIIO::ImageSpec& spec = m_state->spec;
    errno = 0;  // fail() reports the system's reason, e.g. a full disk
    if (!m_state->output->write_scanlines(spec.y + row_begin, spec.y + row_end, spec.z, OIIO::TypeFloat, pixels))
        fail(fmt::format("cannot write rows {}-{}", row_begin, row_end - 1));
}

void FrameOutput::commit()
{
    if (m_state->zip_writer) {
        m_state->zip_writer->finish();
        m_state->zip_writer.reset();
    } else if (m_state->multipart_writer) {
        m_state->multipart_writer->finish();
        m_state->multipart_writer.reset();
    } else {
        errno = 0;  // fail() reports the system's reason, e.g. a full disk
        if (!m_state->output->close())
            fail("cannot finish writing");
        m_state->output.reset();
    }
    std::error_code error;
    stdfs::rename(m_temporary_path, m_path, error);
    if (error)
        throw bad_input(m_path, fmt::format("cannot rename the finished file into place ({})", error.message()));
    m_committed = true;
}

void check_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs)
{
    std::set<std::string> input_paths;
    for (const std::string& input : inputs)
        input_paths.insert(stdfs::weakly_canonical(input).string());
    std::set<std::string> checked_directories;
    for (const std::string& output : outputs) {
        if (input_paths.count(stdfs::weakly_canonical(output).string()))
            throw usage_error(fmt::format("output '{}' is also an input; modestack never overwrites its input", output));
        stdfs::path directory = stdfs::path(output).parent_path();
        if (directory.empty())
            directory = ".";
        if (!checked_directories.insert(directory.string()).second)
            continue;
        std::error_code error;
        if (stdfs::exists(directory, error) && !stdfs::is_directory(directory, error))
            throw bad_input(directory.string(), "output directory is a file");
        stdfs::create_directories(directory, error);
        if (error)
            throw bad_input(directory.string(), fmt::format("cannot create output directory ({})", error.message()));
        if (access(directory.c_str(), W_OK) != 0)
            throw bad_input(directory.string(), "output directory is not writable");
    }
}

}  // namespace modestack::io
