// Internal to io/: reads rows of a ZIP or ZIPS scanline EXR part (of a single-
// or multi-part file) in its native pixel types, with OpenEXR's Core API for the chunks and libdeflate to
// inflate them (about twice zlib's speed; the zlib streams are the same). The
// counterpart of zip_scanline_writer.h; a streamed denoise decodes each input
// row up to three times, so decoding matters as much as encoding there.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct OpenFrame;
struct OpenPart;

/// Where each channel of a ZIP/ZIPS part sits in a decoded chunk.
struct ZipLayout {
    int part = 0;                 ///< the part's index in the file
    int lines_per_chunk = 16;     ///< 16 for ZIP, 1 for ZIPS
    int first_y = 0;              ///< the data window's first row
    std::size_t row_bytes = 0;    ///< one decoded scanline: channel after channel
    /// For each channel in OpenImageIO's order: its byte offset in a decoded
    /// scanline (its samples run from there) and the bytes of one sample.
    std::vector<std::size_t> offset, bytes;
};

/// The layout of `part` of `frame`'s file when it is a ZIP or ZIPS scanline
/// part without subsampled channels, else nullptr (the caller reads with
/// OpenImageIO).
std::shared_ptr<const ZipLayout> zip_layout(const OpenFrame& frame, const OpenPart& part);

/// Reads rows [row_begin, row_end) (0 = the data window's first row) of channels
/// [channel_begin, channel_end) (OpenImageIO's order within the part) of the
/// part of `frame`'s file whose layout is `layout`, in native types packed per pixel, as OpenImageIO's
/// read_scanlines with TypeUnknown does. Thread-safe. Throws Error naming the
/// file on a chunk that cannot be read or decoded.
void read_zip_rows(const OpenFrame& frame, const ZipLayout& layout, int row_begin, int row_end, int channel_begin,
                   int channel_end, unsigned char* destination);

}  // namespace modestack::io::detail
