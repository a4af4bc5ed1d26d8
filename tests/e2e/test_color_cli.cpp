// End-to-end colour management: an sRGB-encoded noisy sequence denoised with
// --colorspace comes back in sRGB encoding, closer to the truth than its input
// and than denoising the encoded values as if they were light; a scene-linear
// EXR is left as it is; the JSON and EXR provenance name the config and space;
// unknown names and broken configs fail before anything is written.
#include "tests/tools/testkit.h"

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace modestack;
using testkit::run_modestack;
using testkit::read_text;
using testkit::TempDir;

namespace {
constexpr int kWidth = 32, kHeight = 24, kFrames = 16;

// Rank-2 light in scene-linear units: a fixed pattern brightening, and a
// second pattern fading in.
float clean_linear(int frame, int x, int y, int c)
{
    float t = static_cast<float>(frame) / kFrames;
    float mode1 = 0.3f + 0.2f * std::sin(0.25f * x + 0.1f * c) * std::cos(0.2f * y);
    float mode2 = 0.5f * (x > kWidth / 2 ? 1.0f : 0.1f) + 0.05f * c;
    return mode1 * (1.0f + 0.5f * t) + mode2 * t * t;
}

float noise(int frame, int x, int y, int c)
{
    std::mt19937 generator(static_cast<unsigned>(((frame * 131 + x) * 977 + y) * 7 + c));
    std::normal_distribution<float> normal(0.0f, 0.08f);
    return normal(generator);
}

// The sRGB encoding as OCIO's moncurve (gamma 2.4, offset 0.055) defines it.
float encode_srgb(float linear)
{
    const double gamma = 2.4, offset = 0.055;
    const double break_linear = std::pow(offset * gamma / ((gamma - 1.0) * (1.0 + offset)), gamma);
    const double slope =
        std::pow((gamma - 1.0) / offset, gamma - 1.0) * std::pow((1.0 + offset) / gamma, gamma);
    double v = linear;
    return static_cast<float>(v <= break_linear ? v / slope
                                                : (1.0 + offset) * std::pow(v, 1.0 / gamma) - offset);
}

testkit::ExrLayout float_rgb()
{
    testkit::ExrLayout layout;
    layout.width = kWidth;
    layout.height = kHeight;
    layout.channel_types = {"float", "float", "float"};
    return layout;
}

// Mean square difference of a sequence's RGB from the encoded truth.
double mse_against_encoded_truth(const std::string& printf_pattern)
{
    double sum = 0;
    for (int frame = 1; frame <= kFrames; ++frame) {
        char name[4096];
        std::snprintf(name, sizeof name, printf_pattern.c_str(), frame);
        std::vector<float> rgb = testkit::read_channels(name, {"R", "G", "B"});
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c) {
                    double d = rgb[(y * kWidth + x) * 3 + c] - encode_srgb(clean_linear(frame, x, y, c));
                    sum += d * d;
                }
    }
    return sum / (static_cast<double>(kFrames) * kWidth * kHeight * 3);
}

// The tests use the shipped config unless they say otherwise.
struct NoOcioVariable {
    NoOcioVariable() { unsetenv("OCIO"); }
};

} // namespace

TEST_CASE("an sRGB-encoded sequence is denoised in scene-linear and returned in sRGB, closer to the truth")
{
    NoOcioVariable no_ocio;
    TempDir dir;
    std::filesystem::create_directories(dir.file("in"));
    testkit::write_sequence(
        dir.file("in/shot.%04d.exr"),
        [] {
            std::vector<int> frames;
            for (int f = 1; f <= kFrames; ++f)
                frames.push_back(f);
            return frames;
        }(),
        float_rgb(),
        [](int frame, int x, int y, int c) {
            return encode_srgb(clean_linear(frame, x, y, c) + noise(frame, x, y, c));
        });
    auto result = run_modestack("denoise " + dir.file("in/shot.####.exr") + " --colorspace sRGB -o " +
                                dir.file("out/shot.####.exr") + " --json " + dir.file("color.json") + " -q");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    auto plain = run_modestack("denoise " + dir.file("in/shot.####.exr") + " -o " +
                               dir.file("plain/shot.####.exr") + " -q");
    REQUIRE_MESSAGE(plain.exit_code == 0, plain.err);

    double noisy = mse_against_encoded_truth(dir.file("in/shot.%04d.exr"));
    double denoised = mse_against_encoded_truth(dir.file("out/shot.%04d.exr"));
    double encoded_as_light = mse_against_encoded_truth(dir.file("plain/shot.%04d.exr"));
    MESSAGE("MSE against the sRGB-encoded truth: noisy " << noisy << ", denoised in linear " << denoised
                                                         << ", denoised as encoded values "
                                                         << encoded_as_light);
    CHECK(denoised < 0.1 * noisy);
    CHECK(denoised < encoded_as_light);

    // Returned in sRGB: the output's mean is the encoded truth's, far from the linear one.
    double output_mean = 0, encoded_mean = 0, linear_mean = 0;
    std::vector<float> rgb = testkit::read_channels(dir.file("out/shot.0009.exr"), {"R", "G", "B"});
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            for (int c = 0; c < 3; ++c) {
                output_mean += rgb[(y * kWidth + x) * 3 + c];
                encoded_mean += encode_srgb(clean_linear(9, x, y, c));
                linear_mean += clean_linear(9, x, y, c);
            }
    CHECK(std::fabs(output_mean - encoded_mean) < 0.01 * encoded_mean);
    CHECK(std::fabs(linear_mean - encoded_mean) > 0.1 * encoded_mean);

    auto json = nlohmann::json::parse(read_text(dir.file("color.json")));
    CHECK(json["color"]["input_space"] == "sRGB Encoded Rec.709 (sRGB)");
    CHECK(json["color"]["input_space_from"] == "--colorspace");
    CHECK(json["color"]["converted"] == true);
    CHECK(json["color"]["scene_linear"] == "Linear Rec.709 (sRGB)");
    CHECK(json["color"]["ocio_config_from"] == "shipped");
    CHECK(json["color"]["ocio_config_name"] == "modestack-default");
    std::string config = json["color"]["ocio_config"];
    CHECK(testkit::read_string_attribute(dir.file("out/shot.0001.exr"), "modestack:ocio_config") == config);
    CHECK(testkit::read_string_attribute(dir.file("out/shot.0001.exr"), "modestack:colorspace") ==
          "sRGB Encoded Rec.709 (sRGB)");
}

TEST_CASE("a scene-linear EXR is not converted, and --ocio-config wins over $OCIO")
{
    TempDir dir;
    testkit::write_sequence(dir.file("shot.%04d.exr"), {1, 2, 3, 4}, float_rgb(),
                            [](int frame, int x, int y, int c) { return clean_linear(frame, x, y, c); });
    setenv("OCIO", dir.file("absent.ocio").c_str(), 1);
    auto from_environment =
        run_modestack("denoise " + dir.file("shot.####.exr") + " -o " + dir.file("a.####.exr"));
    CHECK(from_environment.exit_code == 1);
    CHECK(from_environment.err.find("absent.ocio: no such file (the OpenColorIO config from $OCIO)") !=
          std::string::npos);
    std::string shipped = std::string(MODESTACK_SOURCE_DIR) + "/share/ocio/config.ocio";
    auto result = run_modestack("denoise " + dir.file("shot.####.exr") + " --ocio-config " + shipped +
                                " -o " + dir.file("b.####.exr") + " --json " + dir.file("b.json") + " -q");
    unsetenv("OCIO");
    REQUIRE_MESSAGE(result.exit_code == 0, result.err);
    auto json = nlohmann::json::parse(read_text(dir.file("b.json")));
    CHECK(json["color"]["ocio_config_from"] == "--ocio-config");
    CHECK(json["color"]["input_space_from"] == "OpenEXR default");
    CHECK(json["color"]["converted"] == false);
}

TEST_CASE("an unknown colour space, display or view, or a broken config, fails before anything is written")
{
    NoOcioVariable no_ocio;
    TempDir dir;
    std::filesystem::create_directories(dir.file("in"));
    testkit::write_sequence(dir.file("in/shot.%04d.exr"), {1, 2, 3, 4}, float_rgb(),
                            [](int frame, int x, int y, int c) { return clean_linear(frame, x, y, c); });
    auto unknown = run_modestack("denoise " + dir.file("in/shot.####.exr") + " --colorspace nonsense -o " +
                                 dir.file("out/shot.####.exr"));
    CHECK(unknown.exit_code == 2);
    CHECK(unknown.err.find("--colorspace 'nonsense': no such colour space") != std::string::npos);
    CHECK(unknown.err.find("available: Linear Rec.709 (sRGB), ACEScg") != std::string::npos);

    std::ofstream(dir.file("broken.ocio")) << "ocio_profile_version: 2\ncolorspaces: [oops\n";
    auto broken = run_modestack("denoise " + dir.file("in/shot.####.exr") + " --ocio-config " +
                                dir.file("broken.ocio") + " -o " + dir.file("out/shot.####.exr"));
    CHECK(broken.exit_code == 1);
    CHECK(broken.err.find(dir.file("broken.ocio") +
                          ": not a usable OpenColorIO config (the OpenColorIO config "
                          "from --ocio-config)") != std::string::npos);
    CHECK(testkit::list_directory(dir.file("out")).empty());

    auto display = run_modestack("run --display P3 -o " + dir.file("run") + " -q");
    CHECK(display.exit_code == 2);
    CHECK(display.err.find("--display 'P3': no such display") != std::string::npos);
    auto view = run_modestack("run --view Filmic -o " + dir.file("run") + " -q");
    CHECK(view.exit_code == 2);
    CHECK(view.err.find("available: Standard, Raw") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("run")));
}
