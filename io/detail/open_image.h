// Internal to io/: how every reader opens an input image. It opens with the reader
// the file extension names, and only that one: OIIO's ImageInput::open() and
// create(filename) fall back to trying every reader on the bytes when the named one
// fails, and some of those abort the process on garbage (a damaged .exr taken for an
// RLA file hit an assertion in OIIO's RLA reader: exit 134; found by fuzz/exr_header).
// open_checked_image() adds the checks that come before the reader, shared by
// `info` (frame_header.cpp) and the sequence reader, so both say the same thing
// about the same bad file.
#pragma once

#include "core/common/error.h"

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

namespace modestack::io::detail {

/// The opened image, or null with `reason` saying why not.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& file, std::string& reason);

/// Opens `file` for reading after refusing what would mislead or hurt the reader:
/// a missing file, a directory, an empty file, an EXR header whose attributes claim
/// more bytes than the file holds. Throws a bad-input Error naming the file (and
/// `frame_number`, when given) on any of those or when no reader can open it.
std::unique_ptr<OIIO::ImageInput> open_checked_image(const std::string& file, int frame_number = kNoFrame);

}  // namespace modestack::io::detail
