// Small text outputs (JSON summaries, CSV) written atomically: to a temporary
// name beside the target, renamed into place when complete.
#pragma once

#include <string>

namespace modestack::io {

/// Writes `text` to `path` atomically. Throws Error (bad input) naming the path on failure.
void write_text_file(const std::string& path, const std::string& text);

/// Sets the number of threads OpenImageIO and OpenEXR may use (0 = all cores).
void set_io_threads(int threads);

}  // namespace modestack::io
