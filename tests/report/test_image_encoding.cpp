// The report's image transport: base64 and PNG round trips are exact, the log
// encoding keeps every in-range value within half a code step (in stops), and
// the linear quantization of coefficient images within half its scale.
#include "app/report/image_encoding.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace modestack;
using namespace modestack::app::report;

TEST_CASE("base64 matches RFC 4648's examples and round-trips every length")
{
    auto bytes = [](const std::string& text) { return std::vector<std::uint8_t>(text.begin(), text.end()); };
    CHECK(base64_encode(bytes("")) == "");
    CHECK(base64_encode(bytes("f")) == "Zg==");
    CHECK(base64_encode(bytes("fo")) == "Zm8=");
    CHECK(base64_encode(bytes("foo")) == "Zm9v");
    CHECK(base64_encode(bytes("foobar")) == "Zm9vYmFy");
    std::mt19937 generator(5);
    for (size_t length = 0; length < 40; ++length) {
        std::vector<std::uint8_t> data(length);
        for (auto& byte : data)
            byte = static_cast<std::uint8_t>(generator());
        CHECK(base64_decode(base64_encode(data)) == data);
    }
    CHECK_THROWS(base64_decode("Zm9v*"));
}

TEST_CASE("PNG encoding round-trips 8-bit images of 1 to 4 channels and odd sizes exactly")
{
    std::mt19937 generator(7);
    for (int channels = 1; channels <= 4; ++channels)
        for (auto [width, height] : {std::pair{1, 1}, std::pair{257, 3}, std::pair{5, 89}}) {
            io::Image8 image{width, height, channels, {}};
            image.pixels.resize(static_cast<size_t>(width) * height * channels);
            for (auto& value : image.pixels)
                value = static_cast<std::uint8_t>(generator());
            io::Image8 back = io::decode_png(io::encode_png(image));
            CHECK(back.width == width);
            CHECK(back.height == height);
            CHECK(back.channels == channels);
            CHECK(back.pixels == image.pixels);
        }
    CHECK(png_data_uri({1, 1, 3, {1, 2, 3}}).rfind("data:image/png;base64,iVBORw0KGgo", 0) == 0);
    CHECK_THROWS(io::decode_png({1, 2, 3, 4}));
}

TEST_CASE("log encoding keeps values within half a code step and maps zero and negatives to code 0")
{
    LinearImage image{64, 16, {}};
    std::mt19937 generator(11);
    std::uniform_real_distribution<double> stops(-10.0, 3.0);
    for (int i = 0; i < 64 * 16 * 3; ++i)
        image.rgb.push_back(static_cast<float>(std::exp2(stops(generator))));
    image.rgb[0] = 0.0f;
    image.rgb[1] = -2.0f;
    image.rgb[2] = NAN;
    const double range = 16.0;
    LogImage encoded = log_encode(image, range);
    CHECK(encoded.high - encoded.low == doctest::Approx(range));
    CHECK(encoded.image.pixels[0] == 0);
    CHECK(encoded.image.pixels[1] == 0);
    CHECK(encoded.image.pixels[2] == 0);
    CHECK(log_decode(encoded, 0) == 0.0);
    // Half a step of 16 stops over 255 codes: 2^(16/510) − 1 ≈ 2.2 %.
    const double bound = std::exp2(range / 255.0 / 2.0) - 1.0 + 1e-6;
    double worst = 0;
    for (size_t i = 3; i < image.rgb.size(); ++i) {
        double value = image.rgb[i];
        if (std::log2(value) < encoded.low || std::log2(value) > encoded.high)
            continue;
        worst = std::max(worst, std::abs(log_decode(encoded, encoded.image.pixels[i]) / value - 1.0));
    }
    CHECK(worst > 0.0);
    CHECK(worst <= bound);
}

TEST_CASE("linear quantization stays within half its scale and keeps the extremes exactly")
{
    LinearImage image{33, 7, {}};
    std::mt19937 generator(13);
    std::normal_distribution<float> normal(0.0f, 3.0f);
    for (int i = 0; i < 33 * 7 * 3; ++i)
        image.rgb.push_back(normal(generator));
    QuantizedImage quantized = quantize(image);
    double worst = 0;
    for (size_t i = 0; i < image.rgb.size(); ++i)
        worst = std::max(worst, std::abs(quantized.offset + quantized.scale * quantized.image.pixels[i] - image.rgb[i]));
    CHECK(worst <= quantized.scale / 2 * (1 + 1e-6));
    auto [smallest, largest] = std::minmax_element(image.rgb.begin(), image.rgb.end());
    CHECK(quantized.offset == doctest::Approx(*smallest));
    CHECK(quantized.offset + 255 * quantized.scale == doctest::Approx(*largest));

    LinearImage flat{2, 2, std::vector<float>(12, 0.25f)};
    QuantizedImage constant = quantize(flat);
    CHECK(constant.image.channels == 1);  // grey travels as one channel
    CHECK(constant.offset + constant.scale * constant.image.pixels[3] == doctest::Approx(0.25));
}
