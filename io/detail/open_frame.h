// Internal to io/: one opened input frame (OIIO types), shared by the sequence
// reader and the frame writer. Nothing outside io/ includes this header.
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct ZipLayout;

struct OpenFrame {
    std::string file;
    int frame_number = 0;
    std::unique_ptr<OIIO::ImageInput> input;
    OIIO::ImageSpec spec;
    std::vector<int> selected;      ///< channel index of each selected channel in this file
    std::vector<size_t> byte_offset;  ///< byte offset of each channel in a native pixel
    size_t native_pixel_bytes = 0;
    /// Set for a single-part ZIP/ZIPS scanline file read with ExrCodec::Libdeflate:
    /// its rows are decoded with libdeflate (zip_scanline_reader.h), not through `input`.
    std::shared_ptr<const ZipLayout> zip_layout;
};

}  // namespace modestack::io::detail
