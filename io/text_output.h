// Small text outputs (JSON summaries, CSV) written atomically: to a temporary
// name beside the target, renamed into place when complete.
#pragma once

#include <string>

namespace modestack::io {

/// Writes `text` to `path` atomically. Throws Error (bad input) naming the path on failure.
void write_text_file(const std::string& path, const std::string& text);

/// Sets the number of threads OpenImageIO and OpenEXR may use (0 = all cores).
void set_io_threads(int threads);

/// Makes OpenEXR decode and encode each file on the calling thread, for commands
/// that keep one file per frame open and work on frames in parallel themselves:
/// OpenEXR's own threads would add nothing there, and each open file would hold
/// 2 × threads line buffers (about 1 MB each at 1920 wide) instead of one.
void use_single_threaded_exr_files();

}  // namespace modestack::io
