// --exr-codec libdeflate|openimageio, a benchmarking option of the subcommands
// that read or write EXR pixels: which code decodes and encodes ZIP/ZIPS
// scanline files (io/exr_codec.h). It never changes a pixel; it lets a
// benchmark time OpenImageIO's path against the default in the same binary.
#pragma once

#include "io/exr_codec.h"

#include <CLI/CLI.hpp>

namespace modestack::app {

/// Adds --exr-codec to `command`, under the "Benchmarking" heading of its --help.
void add_exr_codec_option(CLI::App& command, io::ExrCodec& codec);

}  // namespace modestack::app
