// Internal to io/: one opened input frame (OIIO types), shared by the sequence
// reader and the frame writers. A multi-part EXR is presented as one image:
// every part's channels in part order, named as layers (those of a part with
// bare channels such as `R` are `<part name>.R`, see sequence_reader.cpp);
// `parts` says where each part's channels lie. Nothing outside io/ includes
// this header.
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct ZipLayout;

/// One part (OIIO subimage) of an opened frame; a single-part file has one.
struct OpenPart {
    int subimage = 0;
    std::string name;              ///< the part's name ("" for a single-part file without one)
    OIIO::ImageSpec spec;          ///< as OIIO reads the part: the file's own channel names
    int first_channel = 0;         ///< its first channel in the frame's channel list
    size_t byte_offset = 0;        ///< where its channels start in a native pixel of the frame
    size_t native_pixel_bytes = 0; ///< its channels' bytes in a native pixel
    /// Set for a ZIP/ZIPS scanline part read with ExrCodec::Libdeflate: its rows
    /// are decoded with libdeflate (zip_scanline_reader.h), not through OIIO.
    std::shared_ptr<const ZipLayout> zip_layout;
};

struct OpenFrame {
    std::string file;
    int frame_number = 0;
    std::unique_ptr<OIIO::ImageInput> input;
    /// The frame as one image: a single-part file's spec; for a multi-part file,
    /// part 0's with every part's channels (names as layers, formats) in part order.
    OIIO::ImageSpec spec;
    std::vector<OpenPart> parts;      ///< every part, part 0 first
    std::vector<int> selected;        ///< channel index of each selected channel in this file
    std::vector<size_t> byte_offset;  ///< byte offset of each channel in a native pixel
    size_t native_pixel_bytes = 0;

    bool multipart() const { return parts.size() > 1; }
    /// The part holding channel `channel` of `spec`.
    const OpenPart& part_of(int channel) const
    {
        size_t p = parts.size() - 1;
        while (p > 0 && parts[p].first_channel > channel)
            --p;
        return parts[p];
    }
};

}  // namespace modestack::io::detail
