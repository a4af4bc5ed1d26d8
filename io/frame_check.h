// Whether a frame file is whole and readable, for `modestack info`: by default
// its chunk offset tables against its size (cheap; finds a file cut short), and
// with `info --check` a decode of every chunk of every part and level as well
// (finds damaged data inside a file of the right size too).
#pragma once

#include <string>

namespace modestack::io {

/// The problem found in `file`'s chunk offset tables (one line, e.g.
/// "truncated: ..."), or "" when none or when it is not an EXR file. Reads the
/// headers, the tables and one chunk's leader; never throws for a bad file.
std::string check_chunk_tables(const std::string& file);

/// The problem found decoding every chunk of every part and MIP level of `file`
/// (any image format), or "" when all decode. Never throws for a bad file; call
/// it on a file whose header read_frame_header() has read.
std::string check_every_chunk(const std::string& file);

} // namespace modestack::io
