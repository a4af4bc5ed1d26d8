// Internal to io/: the cheap completeness check of an OpenEXR file that `info`
// runs on every frame: the chunk offset tables read against the file size. A
// file cut short (a copy or render that died, a full disk) fails it; damaged
// bytes inside a chunk pass it (decoding every chunk finds those: frame_check.h).
#pragma once

#include <string>

namespace modestack::io::detail {

/// Checks the chunk offset tables of `file`: they must lie inside the file,
/// every chunk must start after them and inside the file, and the chunk that
/// starts last must end inside it. Reads the headers, the tables and that one
/// chunk's leader. Returns the problem ("truncated: ..."), or "" when the
/// tables are whole or the file is not an OpenEXR file.
std::string exr_chunk_table_problem(const std::string& file);

} // namespace modestack::io::detail
