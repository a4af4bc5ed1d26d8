// Internal to io/: the channels of a copied output as FrameOutput lays out
// each output pixel for its writers (OpenImageIO, the libdeflate ZIP writer,
// the multi-part writer): the input channels it keeps, in the input's order,
// then the added channels, each in the pixel type it is written in, packed.
#pragma once

#include <OpenImageIO/typedesc.h>

#include <cstddef>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct OutputChannel {
    std::string name;       ///< in the frame as one image (layer-prefixed in a multi-part frame)
    OIIO::TypeDesc type;    ///< as written
    std::size_t offset = 0; ///< in an output pixel
    int input_channel = -1; ///< the frame's channel it copies or replaces; -1 for an added channel
};

struct OutputLayout {
    std::vector<OutputChannel> channels;
    std::size_t pixel_bytes = 0;
    /// The compression of each output part, by input part (OpenImageIO's names,
    /// "dwaa:45" with a level; see output_format.h); one entry when the output is single-part.
    std::vector<std::string> compressions;
};

} // namespace modestack::io::detail
