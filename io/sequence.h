// Frame-sequence patterns and frame ranges, as oiiotool writes them:
// `dir/name.####.exr`, `name.%04d.exr`, `name.%d.exr`, `name.@@@@.exr`,
// `name.1-10#.exr`, and ranges `1001-1100`, `1-100x2`, `1,3,7-9`. Patterns are
// parsed with OIIO's Filesystem helpers; the one convention we add is that a run
// of several `#` means one digit each (`####` = 4 digits, as Nuke, Houdini and
// Blender read it), while a lone `#` keeps oiiotool's meaning of 4 digits. As in
// oiiotool and Nuke, `%d` (and `@`) is unpadded and `%04d` is padded to 4 digits:
// a file on disk is a frame when the pattern writes exactly its name.
#pragma once

#include <string>
#include <vector>

namespace modestack::io {

/// A sequence pattern resolved to concrete frames and file names.
struct FrameSequence {
    std::string pattern;             ///< as the user wrote it
    std::string printf_pattern;      ///< normalized, e.g. "dir/name.%04d.exr"
    std::vector<int> frames;         ///< frame numbers, in the order given
    std::vector<std::string> files;  ///< one file name per frame
};

/// Parses a frame range: "7", "1001-1100", "1-100x2", "1,3,7-9" (OIIO syntax).
/// Throws a usage error naming `option` when malformed or empty.
std::vector<int> parse_frame_range(const std::string& spec, const std::string& option = "--frames");

/// Converts a pattern to printf form. Returns false when `pattern` has no frame
/// token (#, @, %d or %0Nd) or is longer than any path (4096 bytes). `embedded_range` receives a range
/// written inside the pattern (`name.1-10#.exr`), or "".
bool normalize_pattern(const std::string& pattern, std::string& printf_pattern,
                       std::string& embedded_range);

/// The frames of a sequence found on disk, in ascending order, gaps allowed: the
/// files whose names the pattern writes for the number in them (name.7.exr for
/// name.%d.exr, name.0007.exr for name.%04d.exr). Throws Error (bad input) when the directory is missing or
/// nothing matches.
FrameSequence scan_input_sequence(const std::string& pattern);

/// The frame numbers missing between the first and last frame of `frames` (ascending).
std::vector<int> missing_frames(const std::vector<int>& frames);

/// Resolves an input sequence. With a non-empty `frame_range` (or a range inside
/// the pattern) exactly those frames are used and each must exist; otherwise
/// the directory is scanned and a gap between the first and last frame found is
/// an error. Throws Error (bad input) naming the pattern or the missing file.
FrameSequence find_input_sequence(const std::string& pattern, const std::string& frame_range = "");

/// Names the files of an output sequence for `frames`. Throws a usage error
/// when the pattern has no frame token and more than one frame is asked for.
FrameSequence output_sequence(const std::string& pattern, const std::vector<int>& frames);

/// A compact description of frame numbers: "1-48", "1-99x2", "1,3,7-9".
std::string describe_frames(const std::vector<int>& frames);

}  // namespace modestack::io
