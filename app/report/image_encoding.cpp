#include "app/report/image_encoding.h"

#include "core/common/error.h"

#include <algorithm>
#include <cmath>

namespace modestack::app::report {
namespace {

const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

io::Image8 rgb_image(const LinearImage& image)
{
    io::Image8 result;
    result.width = image.width;
    result.height = image.height;
    result.channels = 3;
    result.pixels.resize(image.rgb.size());
    return result;
}

// A grey image (every pixel R = G = B) as one channel: a third of the bytes; the
// page's canvas spreads it to RGB again.
io::Image8 grey_if_possible(io::Image8 image)
{
    for (size_t i = 0; i + 2 < image.pixels.size(); i += 3)
        if (image.pixels[i] != image.pixels[i + 1] || image.pixels[i] != image.pixels[i + 2])
            return image;
    io::Image8 grey{image.width, image.height, 1, {}};
    for (size_t i = 0; i < image.pixels.size(); i += 3)
        grey.pixels.push_back(image.pixels[i]);
    return grey;
}

}  // namespace

std::string base64_encode(const std::vector<std::uint8_t>& bytes)
{
    std::string text;
    text.reserve((bytes.size() + 2) / 3 * 4);
    for (size_t i = 0; i < bytes.size(); i += 3) {
        std::uint32_t group = std::uint32_t(bytes[i]) << 16;
        if (i + 1 < bytes.size())
            group |= std::uint32_t(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size())
            group |= bytes[i + 2];
        text += kAlphabet[(group >> 18) & 63];
        text += kAlphabet[(group >> 12) & 63];
        text += i + 1 < bytes.size() ? kAlphabet[(group >> 6) & 63] : '=';
        text += i + 2 < bytes.size() ? kAlphabet[group & 63] : '=';
    }
    return text;
}

std::vector<std::uint8_t> base64_decode(const std::string& text)
{
    std::vector<std::uint8_t> bytes;
    std::uint32_t group = 0;
    int bits = 0;
    for (char character : text) {
        if (character == '=')
            break;
        const char* found = std::find(kAlphabet, kAlphabet + 64, character);
        if (found == kAlphabet + 64)
            throw usage_error("base64 text holds a character outside its alphabet");
        group = (group << 6) | static_cast<std::uint32_t>(found - kAlphabet);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            bytes.push_back(static_cast<std::uint8_t>((group >> bits) & 0xff));
        }
    }
    return bytes;
}

std::string png_data_uri(const io::Image8& image)
{
    return "data:image/png;base64," + base64_encode(io::encode_png(image));
}

LogImage log_encode(const LinearImage& image, double stops)
{
    std::vector<float> brightest;
    brightest.reserve(image.rgb.size() / 3);
    for (size_t i = 0; i + 2 < image.rgb.size(); i += 3) {
        float value = std::max({image.rgb[i], image.rgb[i + 1], image.rgb[i + 2]});
        if (std::isfinite(value) && value > 0)
            brightest.push_back(value);
    }
    double bright_end = 1.0;
    if (!brightest.empty()) {
        auto rank = brightest.begin() + static_cast<std::ptrdiff_t>(0.999 * (brightest.size() - 1));
        std::nth_element(brightest.begin(), rank, brightest.end());
        bright_end = 4.0 * *rank;
    }
    LogImage result;
    result.high = std::log2(bright_end);
    result.low = result.high - stops;
    result.image = rgb_image(image);
    const double codes_per_stop = 255.0 / stops;
    for (size_t i = 0; i < image.rgb.size(); ++i) {
        double value = image.rgb[i];
        double code = std::isfinite(value) && value > 0 ? (std::log2(value) - result.low) * codes_per_stop : 0.0;
        if (std::isnan(value))
            code = 0;
        else if (value == HUGE_VALF)
            code = 255;
        // Values that round to 0 (the darkest kept) become code 1: 0 means "nothing".
        result.image.pixels[i] =
            value > 0 ? static_cast<std::uint8_t>(std::clamp(std::lround(code), 1L, 255L)) : std::uint8_t(0);
    }
    result.image = grey_if_possible(std::move(result.image));
    return result;
}

double log_decode(const LogImage& encoded, int code)
{
    return code <= 0 ? 0.0 : std::exp2(encoded.low + code / 255.0 * (encoded.high - encoded.low));
}

QuantizedImage quantize(const LinearImage& image)
{
    double smallest = 0, largest = 0;
    bool any = false;
    for (float value : image.rgb)
        if (std::isfinite(value)) {
            smallest = any ? std::min<double>(smallest, value) : value;
            largest = any ? std::max<double>(largest, value) : value;
            any = true;
        }
    QuantizedImage result;
    result.offset = smallest;
    result.scale = largest > smallest ? (largest - smallest) / 255.0 : 1.0;
    result.image = rgb_image(image);
    for (size_t i = 0; i < image.rgb.size(); ++i) {
        double value = std::isfinite(image.rgb[i]) ? image.rgb[i] : smallest;
        result.image.pixels[i] =
            static_cast<std::uint8_t>(std::clamp(std::lround((value - smallest) / result.scale), 0L, 255L));
    }
    result.image = grey_if_possible(std::move(result.image));
    return result;
}

}  // namespace modestack::app::report
