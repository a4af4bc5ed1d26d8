// Internal to io/: walks the headers of an OpenEXR file byte by byte, without
// OpenEXR: where they end (the chunk offset tables start there) and whether an
// attribute claims more bytes than the file holds. Shared by the check before
// any reader opens a file (open_image.cpp) and the chunk table check
// (exr_chunk_table.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace modestack::io::detail {

/// What walking an EXR file's headers found.
struct ExrHeaders {
    bool is_exr = false;             ///< the file starts with the OpenEXR magic number
    bool multipart = false;          ///< the version field's multi-part bit
    std::int64_t file_size = 0;      ///< bytes in the file
    std::int64_t tables_offset = -1; ///< where the chunk offset tables start; -1 when the headers end early
    std::string problem;             ///< an attribute larger than the rest of the file, else ""
};

/// Walks the headers of `file` (every part's, for a multi-part file).
ExrHeaders walk_exr_headers(const std::string& file);

} // namespace modestack::io::detail
