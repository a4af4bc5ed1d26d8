// What `modestack info` learns of a sequence: every frame's header and whether
// the frame is whole (io/frame_check.h), each frame checked whatever the others
// gave, so that one run lists every bad frame of a shot.
#pragma once

#include "io/frame_check.h"
#include "io/frame_header.h"
#include "io/sequence.h"

#include <optional>
#include <string>
#include <vector>

namespace modestack::app {

/// How far `info` checks each frame.
enum class FrameCheckDepth {
    ChunkTables, ///< the chunk offset tables against the file size (default)
    EveryChunk,  ///< that, and every chunk decoded (`--check`)
};

/// One frame as `info` found it.
struct CheckedFrame {
    int frame = 0;
    std::string file;
    std::optional<io::FrameHeader> header; ///< absent when the header cannot be read
    std::string problem;                   ///< why the frame is bad, "" when it is fine
};

/// A sequence as `info` found it.
struct InfoFindings {
    io::FrameSequence sequence;
    FrameCheckDepth depth = FrameCheckDepth::ChunkTables;
    std::vector<CheckedFrame> frames; ///< one per frame of `sequence`
    /// The first frame whose header could be read (what `info` describes), or null.
    const CheckedFrame* reference() const;
    /// The frame numbers of the bad frames.
    std::vector<int> bad_frames() const;
};

/// Reads every frame's header and checks it to `depth`.
InfoFindings check_sequence(const io::FrameSequence& sequence, FrameCheckDepth depth);

} // namespace modestack::app
