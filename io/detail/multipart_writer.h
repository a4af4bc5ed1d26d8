// Internal to io/: writes a denoise output whose input is a multi-part EXR, with
// OpenEXR's C++ library, in the input's structure: the same parts in the same
// order, each with its own header copied (name, every attribute) and the
// channels the output keeps of it (in their output types), compressed as the
// output layout says, tiled parts written as scanline parts; a part left with
// no channel (--only-denoised) is left out. Each added channel goes into the
// part of the layer it belongs to. Rows are written
// band after band into every part at once (a multi-part file may interleave its
// parts' chunks; OpenEXR's Core API writes one part after another, so it cannot
// be used here).
#pragma once

#include "io/frame_output.h"

#include <OpenImageIO/typedesc.h>

#include <memory>
#include <string>
#include <vector>

namespace modestack::io::detail {

struct OpenFrame;
struct OutputLayout;

/// Where an added channel goes in a multi-part output: the part of the longest
/// layer of `source` whose name (as presented, see open_frame.h) starts the
/// added channel's name (`L.sigma.R` goes with layer `L`), else part 0. Its name
/// in that part loses the part's name when the part names its channels within
/// itself (bare `R`, G, B: `diffuse.sigma.R` is `sigma.R` in part `diffuse`), so
/// that it reads back under the same name.
struct AddedChannelPlace {
    int part = 0;
    std::string name; ///< the channel's name in the part
};
AddedChannelPlace added_channel_place(const OpenFrame& source, const std::string& channel);

class MultiPartWriter {
public:
    /// A writer for `path` (reported as `reported_path`) that copies the parts of
    /// `source`'s file with the channels of `layout` (the added ones in their
    /// layer's part) and adds `attributes` (to every part). Throws Error when the
    /// file cannot be created.
    MultiPartWriter(const std::string& path, const std::string& reported_path, const OpenFrame& source,
                    const OutputLayout& layout, const std::vector<HeaderAttribute>& attributes);
    ~MultiPartWriter();
    MultiPartWriter(const MultiPartWriter&) = delete;
    MultiPartWriter& operator=(const MultiPartWriter&) = delete;

    /// Writes rows [row_begin, row_end) (0 = the data window's first row), in
    /// increasing order with no gaps, of every part. `pixels` holds them as
    /// the layout given to the constructor says.
    void write_rows(int row_begin, int row_end, const unsigned char* pixels);
    /// Writes the chunk tables and closes the file. Throws Error on failure.
    void finish();

private:
    struct State;
    std::unique_ptr<State> m_state;
};

} // namespace modestack::io::detail
