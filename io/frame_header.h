// What one image file's header says, in plain types: size, windows, channels
// with their pixel types, compression, tiling and attributes. Used by
// `modestack info` and to check that the frames of a sequence agree before any
// work starts.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace modestack::io {

/// An image header summarized for people and for validation.
struct FrameHeader {
    std::string file;
    std::string format_name;  ///< "openexr", ...
    int x = 0, y = 0, width = 0, height = 0;                     ///< data window
    int full_x = 0, full_y = 0, full_width = 0, full_height = 0;  ///< display window
    int tile_width = 0, tile_height = 0;                          ///< 0 for scanline files
    int subimages = 1;                                            ///< parts of a multi-part EXR
    bool deep = false;
    std::vector<std::string> channel_names;
    std::vector<std::string> channel_types;  ///< "half", "float", "uint", one per channel
    std::string compression;
    /// Header attributes as (name, "type value") in a human form.
    std::vector<std::pair<std::string, std::string>> attributes;
};

/// Reads the header of `file`. Throws Error (bad input) naming the file when it
/// is missing, not an image, or unreadable.
FrameHeader read_frame_header(const std::string& file);

/// "160x120" or "160x120+8+4" when the window does not start at 0,0.
std::string describe_window(int x, int y, int width, int height);

}  // namespace modestack::io
