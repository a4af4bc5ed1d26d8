// What one image file's header says, in plain types: size, windows, channels
// with their pixel types, compression, tiling and attributes, and the same for
// every part of a multi-part EXR. Used by `modestack info` and to check that the
// frames of a sequence agree before any work starts.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace modestack::io {

/// One part of a multi-part EXR file (a single-part file, or another format,
/// has one): what `info` lists of each.
struct ImagePart {
    std::string name;                        ///< the part's name, "" when it has none
    int x = 0, y = 0, width = 0, height = 0; ///< data window
    int tile_width = 0, tile_height = 0;     ///< 0 for scanline parts
    bool deep = false;
    std::vector<std::string> channel_names;
    std::vector<std::string> channel_types;  ///< "half", "float", "uint", one per channel
    std::string compression;
};

/// An image header summarized for people and for validation. The fields it
/// has as an ImagePart describe part 0, the part every reader reads.
struct FrameHeader : ImagePart {
    std::string file;
    std::string format_name;                                     ///< "openexr", ...
    int full_x = 0, full_y = 0, full_width = 0, full_height = 0; ///< display window
    std::vector<ImagePart> parts;                                ///< every part, part 0 first
    /// Header attributes of part 0 as (name, "type value") in a human form.
    std::vector<std::pair<std::string, std::string>> attributes;
};

/// Reads the header of `file`. Throws Error (bad input) naming the file when it
/// is missing, not an image, or unreadable.
FrameHeader read_frame_header(const std::string& file);

/// Every channel of the frame as the sequence readers name it: part 0's for a
/// single-part file; every part's, in part order, named as part_channel_names
/// (io/layers.h) says, for a multi-part one.
std::vector<std::string> channels_as_read(const FrameHeader& header);

/// The "type value" text of attribute `name`, or nothing when the header lacks it.
std::optional<std::string> find_attribute(const FrameHeader& header, const std::string& name);

/// The value of an attribute's "type value" text (`string "Arnold 7.2"` gives
/// `Arnold 7.2`): what follows the type word, without a string's quotes.
std::string attribute_value(const std::string& typed_value);

/// The number an attribute's "type value" text holds (its whole value), or
/// nothing when that is not a finite number.
std::optional<double> attribute_number(const std::string& typed_value);

/// A count an attribute records: its value when that is a whole number in
/// [1, largest], else nothing.
std::optional<std::int64_t> attribute_count(const std::string& typed_value, std::int64_t largest);

/// "160x120" or "160x120+8+4" when the window does not start at 0,0.
std::string describe_window(int x, int y, int width, int height);

}  // namespace modestack::io
