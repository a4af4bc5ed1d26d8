#include "io/detail/zip_scanline_writer.h"

#include "core/common/error.h"
#include "io/detail/exr_core.h"
#include "io/detail/open_frame.h"
#include "io/detail/output_layout.h"

#include <fmt/format.h>
#include <libdeflate.h>
#include <openexr.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <utility>

namespace modestack::io::detail {
namespace {

// The reason for a failed call: OpenEXR's message, plus the system's (e.g. a full disk).
std::string failure_reason(int system_error)
{
    std::string reason = last_core_message();
    if (system_error != 0)
        reason = reason.empty() ? std::strerror(system_error) : fmt::format("{}: {}", reason, std::strerror(system_error));
    return reason;
}

// The level OpenEXR's C++ library (Imf::Header::zipCompressionLevel) writes ZIP at
// by default, so outputs compress as the OpenImageIO path would.
constexpr int kZipLevel = 4;

// ZIP's reversible pre-pass (OpenEXR internal_zip.c): the even bytes then the
// odd bytes (into `split`), then each byte as the difference from the one
// before it, plus 128 (into `out`). Written as two plain loops the compiler
// vectorises; the bytes are OpenEXR's.
void split_and_difference(const unsigned char* raw, size_t count, unsigned char* split, unsigned char* out)
{
    const size_t pairs = count / 2, second_half = (count + 1) / 2;
    for (size_t i = 0; i < pairs; ++i) {
        split[i] = raw[2 * i];
        split[second_half + i] = raw[2 * i + 1];
    }
    if (count % 2)
        split[pairs] = raw[count - 1];
    if (count > 0)
        out[0] = split[0];
    for (size_t k = 1; k < count; ++k)
        out[k] = static_cast<unsigned char>(split[k] - split[k - 1] + 128);
}

// One compressor per thread, not per file: a shot has hundreds of outputs open.
libdeflate_compressor* thread_compressor()
{
    struct Owner {
        libdeflate_compressor* compressor = libdeflate_alloc_compressor(kZipLevel);
        ~Owner() { libdeflate_free_compressor(compressor); }
    };
    thread_local Owner owner;
    if (!owner.compressor)
        throw std::bad_alloc();
    return owner.compressor;
}

bool exr_type_of(const OIIO::TypeDesc& type, exr_pixel_type_t& exr_type)
{
    if (type == OIIO::TypeDesc::HALF)
        exr_type = EXR_PIXEL_HALF;
    else if (type == OIIO::TypeDesc::FLOAT)
        exr_type = EXR_PIXEL_FLOAT;
    else if (type == OIIO::TypeDesc::UINT)
        exr_type = EXR_PIXEL_UINT;
    else
        return false;
    return true;
}

}  // namespace

struct ZipScanlineWriter::State {
    std::string reported_path;
    exr_context_t context = nullptr;
    int width = 0, height = 0;
    int first_y = 0;          ///< the data window's first row
    int lines_per_chunk = 1;  ///< 16 for ZIP, 1 for ZIPS
    size_t pixel_bytes = 0;   ///< one interleaved output pixel
    struct Channel {
        size_t offset = 0;  ///< in an interleaved pixel
        size_t bytes = 0;
    };
    std::vector<Channel> channels;  ///< in the file's (sorted) order
    size_t row_bytes = 0;           ///< one scanline as stored: channel after channel
    std::vector<unsigned char> chunk;  ///< the rows of the chunk being filled, as stored
    int chunk_row = 0;  ///< first row of that chunk
    int next_row = 0;   ///< the row write_rows expects next

    ~State()
    {
        if (context)
            exr_finish(&context);
    }
};

std::unique_ptr<ZipScanlineWriter>
ZipScanlineWriter::open(const std::string& path, const std::string& reported_path, const OpenFrame& source,
                        const OutputLayout& layout, const std::vector<HeaderAttribute>& attributes)
{
    const OIIO::ImageSpec& spec = source.spec;
    if (source.selected.empty() || source.parts.size() != 1 || layout.compressions.size() != 1)
        return nullptr;
    exr_compression_t compression = EXR_COMPRESSION_ZIP;
    if (layout.compressions.front() == "zips")
        compression = EXR_COMPRESSION_ZIPS;
    else if (layout.compressions.front() != "zip")
        return nullptr;

    // Only what this writer can copy exactly (the OpenImageIO path reports what is wrong with the rest).
    CoreReadContext input(source.file);
    ZipPart input_part;
    exr_attr_box2i_t display_window{};
    if (!input.context || !read_zip_part(input.context, 0, spec, input_part) ||
        exr_get_display_window(input.context, 0, &display_window) != EXR_ERR_SUCCESS)
        return nullptr;
    const exr_attr_chlist_t* input_channels = input_part.channels;
    const exr_attr_box2i_t& data_window = input_part.data_window;
    exr_context_initializer_t initializer = core_initializer();

    // Each output channel: where it sits in an interleaved pixel, by name, its
    // type, and the input's perceptual treatment of it (added ones: as before).
    struct Written {
        State::Channel place;
        exr_pixel_type_t type = EXR_PIXEL_HALF;
        exr_perceptual_treatment_t treatment = EXR_PERCEPTUALLY_LOGARITHMIC;
    };
    std::map<std::string, Written> places;
    std::vector<std::string> order; // the layout's
    for (const OutputChannel& channel : layout.channels) {
        Written written{{channel.offset, channel.type.size()}, EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC};
        if (!exr_type_of(channel.type, written.type) || !places.emplace(channel.name, written).second)
            return nullptr;
        order.push_back(channel.name);
    }
    size_t kept_inputs = 0;
    for (int c = 0; c < input_channels->num_channels; ++c) {
        const auto found = places.find(input_channels->entries[c].name.str);
        if (found != places.end()) {
            found->second.treatment =
                static_cast<exr_perceptual_treatment_t>(input_channels->entries[c].p_linear);
            ++kept_inputs;
        }
    }
    size_t layout_inputs = 0; // every kept input channel must be found in the file under its name
    for (const OutputChannel& channel : layout.channels)
        layout_inputs += channel.input_channel >= 0;
    if (kept_inputs != layout_inputs)
        return nullptr;

    auto state = std::make_unique<State>();
    state->reported_path = reported_path;
    state->width = spec.width;
    state->height = spec.height;
    state->first_y = data_window.min.y;
    state->lines_per_chunk = compression == EXR_COMPRESSION_ZIP ? 16 : 1;
    state->pixel_bytes = layout.pixel_bytes;

    // A header this writer cannot build (an attribute OpenEXR's Core refuses) is
    // left to OpenImageIO too: the temporary file is removed and nullptr returned.
    exr_context_t& output = state->context;
    if (exr_start_write(&output, path.c_str(), EXR_WRITE_FILE_DIRECTLY, &initializer) != EXR_ERR_SUCCESS)
        return nullptr;
    int part = 0;
    // Long attribute and channel names (Cycles writes some) as the input has them.
    bool ok = exr_set_longname_support(output, 1) == EXR_ERR_SUCCESS &&
              exr_add_part(output, nullptr, EXR_STORAGE_SCANLINE, &part) == EXR_ERR_SUCCESS;
    for (size_t k = 0; ok && k < order.size(); ++k) {
        const Written& channel = places.at(order[k]);
        ok = exr_add_channel(output, part, order[k].c_str(), channel.type, channel.treatment, 1, 1) ==
             EXR_ERR_SUCCESS;
    }
    ok = ok && exr_set_compression(output, part, compression) == EXR_ERR_SUCCESS &&
         exr_set_data_window(output, part, &data_window) == EXR_ERR_SUCCESS &&
         exr_set_display_window(output, part, &display_window) == EXR_ERR_SUCCESS &&
         exr_set_lineorder(output, part, EXR_LINEORDER_INCREASING_Y) == EXR_ERR_SUCCESS;
    for (size_t a = 0; ok && a < attributes.size(); ++a) {
        const HeaderAttribute& attribute = attributes[a];
        const char* name = attribute.name.c_str();
        switch (attribute.kind) {
        case HeaderAttribute::Kind::Text: ok = exr_attr_set_string(output, part, name, attribute.text.c_str()) == 0; break;
        case HeaderAttribute::Kind::Integer:
            ok = exr_attr_set_int(output, part, name, static_cast<int32_t>(attribute.integer)) == 0;
            break;
        case HeaderAttribute::Kind::Real:
            ok = exr_attr_set_float(output, part, name, static_cast<float>(attribute.real)) == 0;
            break;
        }
    }
    // Everything else (windows' companions, chromaticities, renderer metadata) as the input has it.
    ok = ok && exr_copy_unset_attributes(output, part, input.context, 0) == EXR_ERR_SUCCESS;
    errno = 0;
    clear_core_message();
    if (ok && exr_write_header(output) != EXR_ERR_SUCCESS)  // the first bytes written: a full disk shows here
        throw bad_input(reported_path, fmt::format("cannot create output ({})", failure_reason(errno)));
    if (!ok) {
        exr_finish(&output);
        output = nullptr;
        std::remove(path.c_str());
        return nullptr;
    }

    const exr_attr_chlist_t* output_channels = nullptr;
    exr_get_channels(output, part, &output_channels);
    for (int c = 0; c < output_channels->num_channels; ++c) {
        const State::Channel& place = places.at(output_channels->entries[c].name.str).place;
        state->channels.push_back(place);
        state->row_bytes += place.bytes * static_cast<size_t>(state->width);
    }
    state->chunk.resize(state->row_bytes * state->lines_per_chunk);
    return std::unique_ptr<ZipScanlineWriter>(new ZipScanlineWriter(std::move(state)));
}

ZipScanlineWriter::ZipScanlineWriter(std::unique_ptr<State> state) : m_state(std::move(state)) {}

ZipScanlineWriter::~ZipScanlineWriter() = default;

void ZipScanlineWriter::write_rows(int row_begin, int row_end, const unsigned char* pixels)
{
    State& state = *m_state;
    if (row_begin != state.next_row || row_end > state.height || row_end < row_begin)
        throw internal_error(fmt::format("rows {}-{} written out of order (expected row {})", row_begin, row_end - 1,
                                         state.next_row));
    const size_t width = static_cast<size_t>(state.width);
    for (int row = row_begin; row < row_end; ++row) {
        // Interleaved pixels to the stored layout: one run of samples per channel.
        const unsigned char* in = pixels + static_cast<size_t>(row - row_begin) * width * state.pixel_bytes;
        unsigned char* out = state.chunk.data() + static_cast<size_t>(row - state.chunk_row) * state.row_bytes;
        for (const State::Channel& channel : state.channels) {
            if (channel.bytes == 2)
                for (size_t x = 0; x < width; ++x)
                    std::memcpy(out + x * 2, in + x * state.pixel_bytes + channel.offset, 2);
            else
                for (size_t x = 0; x < width; ++x)
                    std::memcpy(out + x * 4, in + x * state.pixel_bytes + channel.offset, 4);
            out += width * channel.bytes;
        }
        state.next_row = row + 1;
        if (state.next_row == state.height || state.next_row - state.chunk_row == state.lines_per_chunk)
            write_chunk();
    }
}

void ZipScanlineWriter::write_chunk()
{
    State& state = *m_state;
    const size_t raw_bytes = static_cast<size_t>(state.next_row - state.chunk_row) * state.row_bytes;
    thread_local std::vector<unsigned char> split, predicted, compressed;
    split.resize(raw_bytes);
    predicted.resize(raw_bytes);
    split_and_difference(state.chunk.data(), raw_bytes, split.data(), predicted.data());
    libdeflate_compressor* compressor = thread_compressor();
    compressed.resize(libdeflate_zlib_compress_bound(compressor, raw_bytes));
    const size_t compressed_bytes =
        libdeflate_zlib_compress(compressor, predicted.data(), raw_bytes, compressed.data(), compressed.size());
    // A chunk that does not shrink is stored as is; readers tell by its size.
    const bool stored_raw = compressed_bytes == 0 || compressed_bytes >= raw_bytes;
    errno = 0;
    clear_core_message();
    if (exr_write_scanline_chunk(state.context, 0, state.first_y + state.chunk_row,
                                 stored_raw ? state.chunk.data() : compressed.data(),
                                 stored_raw ? raw_bytes : compressed_bytes) != EXR_ERR_SUCCESS)
        throw bad_input(state.reported_path, fmt::format("cannot write rows {}-{} ({})", state.chunk_row,
                                                         state.next_row - 1, failure_reason(errno)));
    state.chunk_row = state.next_row;
}

void ZipScanlineWriter::finish()
{
    State& state = *m_state;
    if (state.next_row != state.height)
        throw internal_error(fmt::format("output finished after {} of {} rows", state.next_row, state.height));
    errno = 0;
    clear_core_message();
    const exr_result_t result = exr_finish(&state.context);  // frees the context either way
    state.context = nullptr;
    if (result != EXR_ERR_SUCCESS)
        throw bad_input(state.reported_path, fmt::format("cannot finish writing ({})", failure_reason(errno)));
}

}  // namespace modestack::io::detail
