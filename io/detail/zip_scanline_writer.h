// Internal to io/: writes a denoise output whose input is a single-part ZIP or
// ZIPS scanline EXR, with OpenEXR's Core API for the file layout and libdeflate
// for the compression. libdeflate writes the same zlib streams as zlib (any EXR
// reader decodes them) about 1.7x faster and slightly smaller at the same level;
// the output's compression is the bulk of `modestack denoise`'s CPU time.
// OpenEXR 3.2 made the same switch; Debian 12 ships 3.1, which still uses zlib.
#pragma once

#include "io/frame_output.h"

#include <memory>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct OpenFrame;
struct OutputLayout;

class ZipScanlineWriter {
public:
    /// A writer for `path` that copies the header of `source`'s file (every
    /// attribute; line order becomes increasing y) with the channels of
    /// `layout` (the input's it keeps, in their types, then the added ones),
    /// compressed as `layout` says (zip or zips), then `attributes`. nullptr
    /// when the source is not a single-part ZIP/ZIPS scanline file, the
    /// compression is not ZIP/ZIPS, or OpenEXR's Core cannot build the header:
    /// the caller then writes with OpenImageIO. Throws Error when the header
    /// cannot be written.
    static std::unique_ptr<ZipScanlineWriter> open(const std::string& path, const std::string& reported_path,
                                                   const OpenFrame& source, const OutputLayout& layout,
                                                   const std::vector<HeaderAttribute>& attributes);
    ~ZipScanlineWriter();
    ZipScanlineWriter(const ZipScanlineWriter&) = delete;
    ZipScanlineWriter& operator=(const ZipScanlineWriter&) = delete;

    /// Writes rows [row_begin, row_end) (0 = the data window's first row), in
    /// increasing order with no gaps. `pixels` holds them interleaved as the
    /// layout given to open() says. Throws Error on a failed write.
    void write_rows(int row_begin, int row_end, const unsigned char* pixels);
    /// Writes the chunk table and closes the file. Throws Error on failure.
    void finish();

private:
    struct State;
    explicit ZipScanlineWriter(std::unique_ptr<State> state);
    void write_chunk();
    std::unique_ptr<State> m_state;
};

}  // namespace modestack::io::detail
