#include "io/detail/zip_scanline_reader.h"

#include "core/common/error.h"
#include "io/detail/exr_core.h"
#include "io/detail/open_frame.h"

#include <fmt/format.h>
#include <libdeflate.h>
#include <openexr.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <new>

namespace modestack::io::detail {
namespace {

// One decompressor per thread (frames are read in parallel).
libdeflate_decompressor* thread_decompressor()
{
    struct Owner {
        libdeflate_decompressor* decompressor = libdeflate_alloc_decompressor();
        ~Owner() { libdeflate_free_decompressor(decompressor); }
    };
    thread_local Owner owner;
    if (!owner.decompressor)
        throw std::bad_alloc();
    return owner.decompressor;
}

// Undoes ZIP's pre-pass (OpenEXR internal_zip.c): a running sum of the bytes
// less 128 each, then the first half's bytes at the even places and the second
// half's at the odd ones.
void undo_difference_and_split(unsigned char* predicted, std::size_t count, unsigned char* out)
{
    for (std::size_t k = 1; k < count; ++k)
        predicted[k] = static_cast<unsigned char>(predicted[k - 1] + predicted[k] - 128);
    const std::size_t pairs = count / 2, second_half = (count + 1) / 2;
    for (std::size_t i = 0; i < pairs; ++i) {
        out[2 * i] = predicted[i];
        out[2 * i + 1] = predicted[second_half + i];
    }
    if (count % 2)
        out[count - 1] = predicted[pairs];
}

}  // namespace

std::shared_ptr<const ZipLayout> zip_layout(const OpenFrame& frame, const OpenPart& open_part)
{
    const OIIO::ImageSpec& spec = open_part.spec;
    CoreReadContext input(frame.file);
    ZipPart part;
    if (!input.context || !read_zip_part(input.context, open_part.subimage, spec, part))
        return nullptr;
    auto layout = std::make_shared<ZipLayout>();
    layout->part = open_part.subimage;
    layout->lines_per_chunk = part.lines_per_chunk();
    layout->first_y = part.data_window.min.y;
    std::map<std::string, std::pair<std::size_t, std::size_t>> places;  // name → offset, bytes
    for (int c = 0; c < part.channels->num_channels; ++c) {
        const exr_attr_chlist_entry_t& channel = part.channels->entries[c];
        const std::size_t bytes = channel.pixel_type == EXR_PIXEL_HALF ? 2 : 4;
        places[channel.name.str] = {layout->row_bytes, bytes};
        layout->row_bytes += bytes * static_cast<std::size_t>(spec.width);
    }
    for (int c = 0; c < spec.nchannels; ++c) {
        const auto place = places.find(spec.channelnames[c]);
        if (place == places.end() || place->second.second != spec.channelformat(c).size())
            return nullptr;
        layout->offset.push_back(place->second.first);
        layout->bytes.push_back(place->second.second);
    }
    return layout;
}

void read_zip_rows(const OpenFrame& frame, const ZipLayout& layout, int row_begin, int row_end, int channel_begin,
                   int channel_end, unsigned char* destination)
{
    // The same message as a failed OpenImageIO read, with the reason.
    const auto fail = [&](const std::string& reason) {
        throw Error(ErrorKind::BadInput,
                    fmt::format("cannot read rows {}-{} ({})", row_begin, row_end - 1,
                                reason.empty() ? std::string("damaged file") : reason),
                    frame.file, frame.frame_number);
    };
    CoreReadContext input(frame.file);
    if (!input.context)
        fail(last_core_message());
    const std::size_t width = static_cast<std::size_t>(frame.spec.width);
    std::size_t pixel_bytes = 0;
    for (int c = channel_begin; c < channel_end; ++c)
        pixel_bytes += layout.bytes[c];
    thread_local std::vector<unsigned char> packed, predicted, decoded;
    libdeflate_decompressor* decompressor = thread_decompressor();
    const int lines = layout.lines_per_chunk;
    for (int chunk_row = row_begin - row_begin % lines; chunk_row < row_end; chunk_row += lines) {
        exr_chunk_info_t chunk;
        if (exr_read_scanline_chunk_info(input.context, layout.part, layout.first_y + chunk_row, &chunk) !=
            EXR_ERR_SUCCESS)
            fail(last_core_message());
        const std::size_t raw_bytes = static_cast<std::size_t>(chunk.height) * layout.row_bytes;
        if (chunk.unpacked_size != raw_bytes || chunk.packed_size > chunk.unpacked_size || chunk.packed_size == 0)
            fail(fmt::format("corrupt chunk at row {}: sizes do not match the header", chunk_row));
        packed.resize(chunk.packed_size);
        if (exr_read_chunk(input.context, layout.part, &chunk, packed.data()) != EXR_ERR_SUCCESS)
            fail(last_core_message());
        const unsigned char* rows = packed.data();
        if (chunk.packed_size < chunk.unpacked_size) {  // equal sizes: stored as is
            predicted.resize(raw_bytes);
            decoded.resize(raw_bytes);
            std::size_t inflated = 0;
            if (libdeflate_zlib_decompress(decompressor, packed.data(), packed.size(), predicted.data(), raw_bytes,
                                           &inflated) != LIBDEFLATE_SUCCESS ||
                inflated != raw_bytes)
                fail(fmt::format("corrupt chunk at row {} (ZIP data does not inflate to its size)", chunk_row));
            undo_difference_and_split(predicted.data(), raw_bytes, decoded.data());
            rows = decoded.data();
        }
        // The chunk's rows inside the request, channel runs to packed pixels.
        const int first = std::max(row_begin, chunk_row), end = std::min(row_end, chunk_row + chunk.height);
        for (int row = first; row < end; ++row) {
            const unsigned char* scanline = rows + static_cast<std::size_t>(row - chunk_row) * layout.row_bytes;
            unsigned char* out = destination + static_cast<std::size_t>(row - row_begin) * width * pixel_bytes;
            std::size_t out_offset = 0;
            for (int c = channel_begin; c < channel_end; ++c) {
                const unsigned char* samples = scanline + layout.offset[c];
                if (layout.bytes[c] == 2)
                    for (std::size_t x = 0; x < width; ++x)
                        std::memcpy(out + x * pixel_bytes + out_offset, samples + x * 2, 2);
                else
                    for (std::size_t x = 0; x < width; ++x)
                        std::memcpy(out + x * pixel_bytes + out_offset, samples + x * 4, 4);
                out_offset += layout.bytes[c];
            }
        }
    }
}

}  // namespace modestack::io::detail
