// Internal to io/: what OpenEXR's C++ library holds for one open file once its
// rows are read or written through it: three chunks of scanlines (its line
// buffer and the codec's two; heaptrack of a 1080p run). Allocated when the file
// is opened, resident once it is read or written. Our own libdeflate paths hold
// less: the reader's buffers are per thread, the writer's one chunk per file.
#pragma once

#include <cstddef>
#include <cstdint>

namespace modestack::io::detail {

inline std::int64_t openexr_file_buffer_bytes(int width, std::size_t pixel_bytes, int chunk_rows)
{
    constexpr int kChunkBuffers = 3;
    return kChunkBuffers * static_cast<std::int64_t>(width) * static_cast<std::int64_t>(pixel_bytes) *
           chunk_rows;
}

} // namespace modestack::io::detail
