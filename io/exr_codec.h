// Which code decodes and encodes the pixels of single-part ZIP and ZIPS
// scanline EXR files, the usual render output: libdeflate through OpenEXR's
// Core API (io/detail/zip_scanline_*.h, the default: about twice zlib's speed,
// the same pixels, zlib streams any EXR reader decodes) or OpenImageIO, as
// every other file is. The choice is kept for benchmarks against OpenImageIO's
// path; it never changes a pixel.
#pragma once

namespace modestack::io {

enum class ExrCodec {
    Libdeflate,   ///< ZIP/ZIPS scanline files through libdeflate; other files through OpenImageIO
    OpenImageIO,  ///< every file through OpenImageIO
};

}  // namespace modestack::io
