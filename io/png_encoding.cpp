#include "io/png_encoding.h"

#include "core/common/error.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fmt/format.h>

namespace modestack::io {

std::vector<std::uint8_t> encode_png(const Image8& image)
{
    if (image.width <= 0 || image.height <= 0 || image.channels < 1 || image.channels > 4 ||
        image.pixels.size() != static_cast<size_t>(image.width) * image.height * image.channels)
        throw internal_error(fmt::format("cannot encode a {}x{} image of {} channels as PNG", image.width,
                                      image.height, image.channels));
    std::vector<std::uint8_t> bytes;
    OIIO::Filesystem::IOVecOutput proxy(bytes);
    auto output = OIIO::ImageOutput::create("png");
    if (!output)
        throw internal_error("OpenImageIO has no PNG writer");
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::UINT8);
    // Level 6 of zlib: most of 9's size at a fraction of its time on noisy images.
    spec.attribute("png:compressionLevel", 6);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // bytes as given, never premultiplied
    OIIO::Filesystem::IOProxy* pointer = &proxy;
    spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &pointer);
    if (!output->open("memory.png", spec) || !output->write_image(OIIO::TypeDesc::UINT8, image.pixels.data()) ||
        !output->close())
        throw internal_error(fmt::format("PNG encoding failed: {}", output->geterror()));
    return bytes;
}

Image8 decode_png(const std::vector<std::uint8_t>& bytes)
{
    OIIO::Filesystem::IOMemReader proxy(const_cast<std::uint8_t*>(bytes.data()), bytes.size());
    OIIO::ImageSpec config;
    OIIO::Filesystem::IOProxy* pointer = &proxy;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &pointer);
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto input = OIIO::ImageInput::create("png");
    if (!input)
        throw internal_error("OpenImageIO has no PNG reader");
    OIIO::ImageSpec spec;
    if (!input->open("memory.png", spec, config))
        throw bad_input("PNG data", fmt::format("cannot decode ({})", input->geterror()));
    Image8 image;
    image.width = spec.width;
    image.height = spec.height;
    image.channels = spec.nchannels;
    image.pixels.resize(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, image.pixels.data()))
        throw bad_input("PNG data", fmt::format("cannot decode ({})", input->geterror()));
    return image;
}

}  // namespace modestack::io
