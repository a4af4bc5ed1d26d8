#include "io/detail/multipart_writer.h"

#include "core/common/error.h"
#include "io/detail/open_frame.h"
#include "io/detail/output_layout.h"
#include "io/layers.h"
#include "io/output_format.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStdIO.h>
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>

namespace modestack::io::detail {
namespace {

Imf::PixelType exr_type_of(const OIIO::TypeDesc& type)
{
    if (type == OIIO::TypeDesc::HALF)
        return Imf::HALF;
    if (type == OIIO::TypeDesc::FLOAT)
        return Imf::FLOAT;
    if (type == OIIO::TypeDesc::UINT)
        return Imf::UINT;
    throw internal_error(fmt::format("no OpenEXR pixel type for {}", type.c_str()));
}

Imf::Compression exr_compression_of(const std::string& method)
{
    static const std::map<std::string, Imf::Compression> compressions{
        {"none", Imf::NO_COMPRESSION},  {"rle", Imf::RLE_COMPRESSION},   {"zips", Imf::ZIPS_COMPRESSION},
        {"zip", Imf::ZIP_COMPRESSION},  {"piz", Imf::PIZ_COMPRESSION},   {"pxr24", Imf::PXR24_COMPRESSION},
        {"b44", Imf::B44_COMPRESSION},  {"b44a", Imf::B44A_COMPRESSION}, {"dwaa", Imf::DWAA_COMPRESSION},
        {"dwab", Imf::DWAB_COMPRESSION}};
    const auto found = compressions.find(method);
    if (found == compressions.end())
        throw internal_error(fmt::format("no OpenEXR compression named '{}'", method));
    return found->second;
}

// The system's reason for a failed write (e.g. a full disk), after OpenEXR's.
std::string with_system_reason(const std::string& reason, int system_error)
{
    if (system_error == 0)
        return reason;
    return reason.empty() ? std::strerror(system_error)
                          : fmt::format("{}: {}", reason, std::strerror(system_error));
}

} // namespace

AddedChannelPlace added_channel_place(const OpenFrame& source, const std::string& channel)
{
    const OIIO::ImageSpec& spec = source.spec;
    int owner = -1; // the first channel of the longest layer that starts `channel`
    size_t owner_layer_size = 0;
    for (int c = 0; c < spec.nchannels; ++c) {
        std::string layer, component;
        split_channel_name(spec.channelnames[c], layer, component);
        if (layer.empty() || layer.size() < owner_layer_size || channel.size() <= layer.size() ||
            channel.compare(0, layer.size(), layer) != 0 || channel[layer.size()] != '.')
            continue;
        if (owner < 0 || layer.size() > owner_layer_size) {
            owner = c;
            owner_layer_size = layer.size();
        }
    }
    if (owner < 0)
        return {0, channel};
    const OpenPart& part = source.part_of(owner);
    const std::string& name_in_part = part.spec.channelnames[owner - part.first_channel];
    const bool named_by_part = name_in_part != spec.channelnames[owner];  // the part's name was put before it
    if (named_by_part && channel.compare(0, part.name.size() + 1, part.name + ".") == 0)
        return {part.subimage, channel.substr(part.name.size() + 1)};
    return {part.subimage, channel};
}

struct MultiPartWriter::State {
    std::string reported_path;
    std::ofstream file;
    std::unique_ptr<Imf::StdOFStream> stream;
    std::unique_ptr<Imf::MultiPartOutputFile> output;
    std::vector<std::unique_ptr<Imf::OutputPart>> parts;
    struct Channel {
        std::string name; ///< in its part
        std::string full_name; ///< in the frame as one image (layer-prefixed)
        Imf::PixelType type = Imf::HALF;
        size_t offset = 0; ///< in a pixel as write_rows gets it
    };
    std::vector<std::vector<Channel>> channels; ///< per part
    Imath::V2i origin{0, 0};                    ///< the data window's top left corner
    int width = 0, height = 0;
    size_t pixel_bytes = 0;
    int next_row = 0;
};

MultiPartWriter::MultiPartWriter(const std::string& path, const std::string& reported_path,
                                 const OpenFrame& source, const OutputLayout& layout,
                                 const std::vector<HeaderAttribute>& attributes)
    : m_state(std::make_unique<State>())
{
    State& state = *m_state;
    state.reported_path = reported_path;
    state.origin = {source.spec.x, source.spec.y};
    state.width = source.spec.width;
    state.height = source.spec.height;
    state.pixel_bytes = layout.pixel_bytes;
    if (layout.compressions.size() != source.parts.size())
        throw internal_error("a multi-part output needs a compression per part");
    std::vector<std::vector<State::Channel>> by_input_part(source.parts.size());
    for (const OutputChannel& channel : layout.channels) {
        if (channel.input_channel >= 0) {
            const OpenPart& part = source.part_of(channel.input_channel);
            by_input_part[part.subimage].push_back(
                {part.spec.channelnames[channel.input_channel - part.first_channel], channel.name,
                 exr_type_of(channel.type), channel.offset});
            continue;
        }
        const AddedChannelPlace place = added_channel_place(source, channel.name);
        for (const State::Channel& existing : by_input_part[place.part])
            if (existing.name == place.name)
                throw bad_input(reported_path,
                                fmt::format("cannot add channel '{}': part {} of {} has one of that name",
                                            place.name, place.part, source.file));
        by_input_part[place.part].push_back(
            {place.name, channel.name, exr_type_of(channel.type), channel.offset});
    }
    // One part left (--only-denoised) makes a single-part file, whose readers (modestack, Nuke) take
    // bare R, G, B as the default layer whatever the part's name: its channels get their layer's name.
    const bool one_part =
        std::count_if(by_input_part.begin(), by_input_part.end(),
                      [](const std::vector<State::Channel>& kept) { return !kept.empty(); }) == 1;
    try {
        std::vector<Imf::Header> headers;
        {
            Imf::MultiPartInputFile input(source.file.c_str());
            if (input.parts() != static_cast<int>(source.parts.size()))
                throw internal_error(
                    fmt::format("{} has {} parts, not {}", source.file, input.parts(), source.parts.size()));
            for (int p = 0; p < input.parts(); ++p) {
                if (by_input_part[p].empty()) // nothing of it kept: no part
                    continue;
                const Imf::Header& input_header = input.header(p);
                // A copy without what the output changes, not Header::erase: OpenEXR 3.1's
                // erase drops an attribute without deleting it (LeakSanitizer). Tiled parts
                // are written as scanline parts, as a single-part tiled input is; the
                // input's DWA level is no part of the output's compression.
                Imf::Header header;
                for (Imf::Header::ConstIterator attribute = input_header.begin();
                     attribute != input_header.end(); ++attribute)
                    if (std::strcmp(attribute.name(), "tiles") != 0 &&
                        std::strcmp(attribute.name(), "dwaCompressionLevel") != 0 &&
                        std::strcmp(attribute.name(), "channels") != 0)
                        header.insert(attribute.name(), attribute.attribute());
                if (header.hasType() && input_header.hasTileDescription())
                    header.setType(Imf::SCANLINEIMAGE);
                header.lineOrder() = Imf::INCREASING_Y;
                for (State::Channel& channel : by_input_part[p]) {
                    // The input's sampling and perceptual treatment, in the type written.
                    const Imf::Channel* kept = input_header.channels().findChannel(channel.name);
                    Imf::Channel written = kept ? *kept : Imf::Channel(channel.type);
                    written.type = channel.type;
                    if (one_part)
                        channel.name = channel.full_name;
                    header.channels().insert(channel.name, written);
                }
                const CompressionName compression = split_compression(layout.compressions[p]);
                header.compression() = exr_compression_of(compression.method);
                if (compression.dwa_level > 0.0f) { // used, and recorded as OpenImageIO records it
                    header.dwaCompressionLevel() = compression.dwa_level;
                    header.insert("dwaCompressionLevel", Imf::FloatAttribute(compression.dwa_level));
                }
                for (const HeaderAttribute& attribute : attributes) {
                    switch (attribute.kind) {
                    case HeaderAttribute::Kind::Text:
                        header.insert(attribute.name, Imf::StringAttribute(attribute.text));
                        break;
                    case HeaderAttribute::Kind::Integer:
                        header.insert(attribute.name, Imf::IntAttribute(static_cast<int>(attribute.integer)));
                        break;
                    case HeaderAttribute::Kind::Real:
                        header.insert(attribute.name,
                                      Imf::FloatAttribute(static_cast<float>(attribute.real)));
                        break;
                    }
                }
                headers.push_back(header);
                state.channels.push_back(std::move(by_input_part[p]));
            }
        }
        errno = 0;
        state.file.open(path, std::ios::binary | std::ios::trunc);
        if (!state.file)
            throw bad_input(reported_path, with_system_reason("cannot create output", errno));
        state.stream = std::make_unique<Imf::StdOFStream>(state.file, path.c_str());
        state.output = std::make_unique<Imf::MultiPartOutputFile>(*state.stream, headers.data(),
                                                                  static_cast<int>(headers.size()));
        for (size_t p = 0; p < headers.size(); ++p)
            state.parts.push_back(std::make_unique<Imf::OutputPart>(*state.output, static_cast<int>(p)));
    } catch (const Error&) {
        throw;
    } catch (const std::exception& error) {
        throw bad_input(reported_path,
                        with_system_reason(fmt::format("cannot create output ({})", error.what()), errno));
    }
}

MultiPartWriter::~MultiPartWriter()
{
    // An unfinished file is removed by FrameOutput; close it quietly first.
    m_state->parts.clear();
    try {
        m_state->output.reset();
    } catch (...) {
    }
}

void MultiPartWriter::write_rows(int row_begin, int row_end, const unsigned char* pixels)
{
    State& state = *m_state;
    if (row_begin != state.next_row || row_end > state.height || row_end < row_begin)
        throw internal_error(fmt::format("rows {}-{} written out of order (expected row {})", row_begin,
                                         row_end - 1, state.next_row));
    const Imath::V2i origin{state.origin.x, state.origin.y + row_begin};
    const size_t row_bytes = state.pixel_bytes * static_cast<size_t>(state.width);
    errno = 0;
    try {
        for (size_t p = 0; p < state.parts.size(); ++p) {
            Imf::FrameBuffer frame_buffer;
            for (const State::Channel& channel : state.channels[p])
                frame_buffer.insert(channel.name, Imf::Slice::Make(channel.type, pixels + channel.offset,
                                                                   origin, state.width, row_end - row_begin,
                                                                   state.pixel_bytes, row_bytes));
            state.parts[p]->setFrameBuffer(frame_buffer);
            state.parts[p]->writePixels(row_end - row_begin);
        }
    } catch (const std::exception& error) {
        throw bad_input(
            state.reported_path,
            with_system_reason(
                fmt::format("cannot write rows {}-{} ({})", row_begin, row_end - 1, error.what()), errno));
    }
    state.next_row = row_end;
}

void MultiPartWriter::finish()
{
    State& state = *m_state;
    if (state.next_row != state.height)
        throw internal_error(
            fmt::format("output finished after {} of {} rows", state.next_row, state.height));
    errno = 0;
    // The parts write their chunk tables when destroyed, without throwing: the stream's state says if they
    // failed.
    state.parts.clear();
    state.output.reset();
    state.stream.reset();
    state.file.close();
    if (!state.file)
        throw bad_input(state.reported_path, with_system_reason("cannot finish writing", errno));
}

} // namespace modestack::io::detail
