// Internal to io/: opens an image with the reader its file extension names, and
// only that one. OIIO's ImageInput::open() and create(filename) fall back to
// trying every reader on the bytes when the named one fails, and some of those
// abort the process on garbage: a damaged .exr taken for an RLA file hit an
// assertion in OIIO's RLA reader (exit 134; found by fuzz/exr_header).
#pragma once

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

namespace modestack::io::detail {

/// The opened image, or null with `reason` saying why not.
inline std::unique_ptr<OIIO::ImageInput> open_image(const std::string& file, std::string& reason)
{
    std::string extension = OIIO::Filesystem::extension(file, false);
    if (extension.empty()) {
        reason = "no file extension to choose an image reader";
        return nullptr;
    }
    auto input = OIIO::ImageInput::create(extension);  // by extension only: nothing is opened
    if (!input) {
        reason = OIIO::geterror();
        return nullptr;
    }
    OIIO::ImageSpec spec;
    if (!input->open(file, spec)) {
        reason = input->geterror();
        return nullptr;
    }
    return input;
}

}  // namespace modestack::io::detail
