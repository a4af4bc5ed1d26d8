// Internal to io/: how many scanlines a compression puts in one chunk, and what
// OpenEXR's C++ library holds for one open file once its rows are read or
// written through it: three chunks of scanlines (its line buffer and the codec's
// two; heaptrack of a 1080p run). Allocated when the file is opened, resident
// once it is read or written. Our own libdeflate paths hold less: the reader's
// buffers are per thread, the writer's one chunk per file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace modestack::io::detail {

/// Scanlines per chunk of a scanline EXR part compressed with `compression`
/// (OpenEXR's: 1 for none, RLE and ZIPS, 16 for ZIP, 32 for PIZ, PXR24, B44,
/// B44A and DWAA, 256 for DWAB).
inline int scanlines_per_chunk(const std::string& compression)
{
    if (compression == "zip")
        return 16;
    if (compression == "dwab")
        return 256;
    if (compression == "piz" || compression == "pxr24" || compression == "b44" || compression == "b44a" ||
        compression == "dwaa")
        return 32;
    return 1; // none, rle, zips
}

inline std::int64_t openexr_file_buffer_bytes(int width, std::size_t pixel_bytes, int chunk_rows)
{
    constexpr int kChunkBuffers = 3;
    return kChunkBuffers * static_cast<std::int64_t>(width) * static_cast<std::int64_t>(pixel_bytes) *
           chunk_rows;
}

} // namespace modestack::io::detail
