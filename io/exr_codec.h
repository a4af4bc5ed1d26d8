// Which code decodes the pixels of ZIP and ZIPS scanline EXR parts (of single-
// and multi-part files) and encodes those of single-part files, the usual render
// output: libdeflate through OpenEXR's Core API (io/detail/zip_scanline_*.h, the
// default: about twice zlib's speed, the same pixels, zlib streams any EXR
// reader decodes) or OpenImageIO, as every other file is (multi-part outputs
// are written with OpenEXR's C++ library either way). The choice is kept for benchmarks against OpenImageIO's
// path; it never changes a pixel.
#pragma once

namespace modestack::io {

enum class ExrCodec {
    Libdeflate,   ///< ZIP/ZIPS scanline files through libdeflate; other files through OpenImageIO
    OpenImageIO,  ///< every file through OpenImageIO
};

}  // namespace modestack::io
