#include "app/exr_codec_option.h"

#include <string>

namespace modestack::app {

void add_exr_codec_option(CLI::App& command, io::ExrCodec& codec)
{
    command
        .add_option_function<std::string>(
            "--exr-codec",
            [&codec](const std::string& name) {
                if (name == "libdeflate")
                    codec = io::ExrCodec::Libdeflate;
                else if (name == "openimageio")
                    codec = io::ExrCodec::OpenImageIO;
                else
                    throw CLI::ValidationError("--exr-codec",
                                               "'" + name + "' is not one of libdeflate, openimageio");
            },
            "Which code reads and writes the pixels of ZIP/ZIPS scanline EXR files: libdeflate (default; "
            "OpenImageIO for every other file) or openimageio (every file). The same pixels either way; for "
            "benchmarks")
        ->option_text("libdeflate|openimageio")
        ->group("Benchmarking");
}

}  // namespace modestack::app
