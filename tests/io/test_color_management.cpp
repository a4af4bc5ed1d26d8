// Colour management: configs the tests write with a known matrix and a known 1D
// LUT convert as their transforms say; the shipped config's sRGB, ACEScg and
// display transforms give the published values and round-trip exactly; the
// config precedence (--ocio-config, $OCIO, shipped); the colour space an EXR
// records; and errors that list what is available or name the broken file.
#include "core/common/error.h"
#include "io/color_management.h"
#include "io/contact_sheet.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"
#include "tests/tools/testkit.h"

#include <OpenImageIO/imageio.h>
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <optional>
#include <thread>

using namespace modestack;
using testkit::TempDir;

namespace {

void write_text(const std::string& path, const std::string& text)
{
    std::ofstream file(path);
    file << text;
}

// A config with a reference space, a matrix-with-offset space and a 1D LUT space.
std::string write_test_config(const TempDir& dir)
{
    write_text(dir.file("square.spi1d"), "Version 1\nFrom 0.0 1.0\nLength 5\nComponents 1\n{\n"
                                         "0.0\n0.0625\n0.25\n0.5625\n1.0\n}\n");
    write_text(dir.file("test.ocio"), R"(ocio_profile_version: 2
name: modestack-test
search_path: "."
strictparsing: true
roles:
  scene_linear: lin
  default: lin
  reference: lin
file_rules:
  - !<Rule> {name: Default, colorspace: default}
displays:
  screen:
    - !<View> {name: squared, colorspace: lut}
active_displays: [screen]
active_views: [squared]
colorspaces:
  - !<ColorSpace>
    name: lin
    isdata: false
    encoding: scene-linear
  - !<ColorSpace>
    name: mixed
    aliases: [mixed_alias]
    isdata: false
    to_scene_reference: !<MatrixTransform> {matrix: [2, 0, 0, 0, 0, 3, 0, 0, 0, 0.5, 0.5, 0, 0, 0, 0, 1], offset: [0.1, 0, 0, 0]}
  - !<ColorSpace>
    name: lut
    isdata: false
    from_scene_reference: !<FileTransform> {src: square.spi1d, interpolation: linear}
)");
    return dir.file("test.ocio");
}

io::ColorConfig shipped_config()
{
    return io::ColorConfig({io::shipped_color_config_path(), io::ColorConfigSource::Shipped});
}

double srgb_to_linear(double v)
{
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

// Sets or unsets $OCIO for one scope.
class ScopedOcioVariable {
public:
    explicit ScopedOcioVariable(const char* value)
    {
        if (const char* old = std::getenv("OCIO"))
            m_old = old;
        if (value)
            setenv("OCIO", value, 1);
        else
            unsetenv("OCIO");
    }
    ~ScopedOcioVariable()
    {
        if (m_old)
            setenv("OCIO", m_old->c_str(), 1);
        else
            unsetenv("OCIO");
    }

private:
    std::optional<std::string> m_old;
};

} // namespace

TEST_CASE("a matrix colour space converts to scene-linear as its matrix and offset say, and back")
{
    TempDir dir;
    io::ColorConfig config({write_test_config(dir), io::ColorConfigSource::CommandLine});
    CHECK(config.name() == "modestack-test");
    CHECK(config.find_color_space("mixed_alias", "--colorspace") == "mixed");
    CHECK_FALSE(config.is_scene_linear("mixed"));
    CHECK(config.is_scene_linear("lin"));
    io::ColorConverter converter(config, "mixed");
    CHECK_FALSE(converter.is_identity());
    // Two RGBA pixels: alpha must pass untouched.
    std::vector<float> pixels{0.25f, 0.5f, 1.0f, 0.7f, -1.0f, 2.0f, 4.0f, 0.3f};
    const std::vector<float> original = pixels;
    converter.to_scene_linear(pixels.data(), 2, 4);
    for (int p = 0; p < 2; ++p) {
        const float* in = original.data() + p * 4;
        CHECK(pixels[p * 4 + 0] == doctest::Approx(2.0 * in[0] + 0.1).epsilon(1e-6));
        CHECK(pixels[p * 4 + 1] == doctest::Approx(3.0 * in[1]).epsilon(1e-6));
        CHECK(pixels[p * 4 + 2] == doctest::Approx(0.5 * in[1] + 0.5 * in[2]).epsilon(1e-6));
        CHECK(pixels[p * 4 + 3] == in[3]);
    }
    converter.from_scene_linear(pixels.data(), 2, 4);
    for (size_t i = 0; i < pixels.size(); ++i)
        CHECK(pixels[i] == doctest::Approx(original[i]).epsilon(1e-6));
}

TEST_CASE("a 1D LUT colour space interpolates its table, and the display uses it")
{
    TempDir dir;
    io::ColorConfig config({write_test_config(dir), io::ColorConfigSource::CommandLine});
    io::ColorConverter converter(config, "lut");
    // from scene-linear = the table x^2 sampled at 0, .25, .5, .75, 1, linearly interpolated.
    std::vector<float> rgb{0.5f, 0.375f, 1.0f};
    converter.from_scene_linear(rgb.data(), 1);
    CHECK(rgb[0] == doctest::Approx(0.25).epsilon(1e-6));
    CHECK(rgb[1] == doctest::Approx((0.0625 + 0.25) / 2).epsilon(1e-6));
    CHECK(rgb[2] == doctest::Approx(1.0).epsilon(1e-6));
    io::DisplayConverter display(config, "", "", 1.0); // defaults: screen / squared, one stop up
    CHECK(display.display() == "screen");
    CHECK(display.view() == "squared");
    std::vector<float> shown{0.25f, 0.1875f, 0.0f};
    display.apply(shown.data(), 1);
    CHECK(shown[0] == doctest::Approx(0.25).epsilon(1e-6));
    CHECK(shown[1] == doctest::Approx((0.0625 + 0.25) / 2).epsilon(1e-6));
    CHECK(shown[2] == doctest::Approx(0.0).epsilon(1e-6));
}

TEST_CASE("the shipped config: sRGB and ACEScg give the published values and round-trip to float precision")
{
    io::ColorConfig config = shipped_config();
    CHECK(config.scene_linear_space() == "Linear Rec.709 (sRGB)");
    CHECK(config.find_color_space("Linear", "--colorspace") == "Linear Rec.709 (sRGB)");
    CHECK(config.is_scene_linear("ACEScg"));
    CHECK_FALSE(config.is_scene_linear("sRGB"));
    CHECK(config.displays() == std::vector<std::string>{"sRGB", "Rec.1886"});

    io::ColorConverter srgb(config, "sRGB");
    std::vector<float> values;
    for (int i = -200; i <= 800; ++i)
        values.push_back(static_cast<float>(i) / 200.0f); // -1 to 4, negatives and over-range included
    values.resize(values.size() / 3 * 3);
    std::vector<float> linear = values;
    srgb.to_scene_linear(linear.data(), linear.size() / 3);
    double worst_formula = 0, worst_round_trip = 0;
    // Above the toe: OCIO's sRGB (a moncurve, continuous at its break 0.0393)
    // and IEC 61966-2-1's rounded constants (break 0.04045) differ only below.
    for (size_t i = 0; i < values.size(); ++i)
        if (values[i] >= 0.05f)
            worst_formula = std::max(worst_formula, std::fabs(linear[i] - srgb_to_linear(values[i])) /
                                                        std::max(1e-3, srgb_to_linear(values[i])));
    std::vector<float> back = linear;
    srgb.from_scene_linear(back.data(), back.size() / 3);
    for (size_t i = 0; i < values.size(); ++i)
        worst_round_trip =
            std::max(worst_round_trip, static_cast<double>(std::fabs(back[i] - values[i])) /
                                           std::max(1e-3, std::fabs(static_cast<double>(values[i]))));
    MESSAGE("sRGB vs IEC 61966-2-1 formula: worst relative error " << worst_formula << ", round trip "
                                                                   << worst_round_trip);
    CHECK(worst_formula < 2e-6);
    CHECK(worst_round_trip < 2e-6);

    // Linear Rec.709 red in ACEScg is the first column of the Bradford-adapted matrix.
    io::ColorConverter acescg(config, "ACEScg");
    std::vector<float> rgb{1.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f};
    acescg.from_scene_linear(rgb.data(), 2);
    CHECK(rgb[0] == doctest::Approx(0.6130974024).epsilon(1e-6));
    CHECK(rgb[1] == doctest::Approx(0.0701937225).epsilon(1e-6));
    CHECK(rgb[2] == doctest::Approx(0.0206155929).epsilon(1e-6));
    for (int c = 3; c < 6; ++c)
        CHECK(rgb[c] == doctest::Approx(1.0).epsilon(1e-6)); // white stays white
}

TEST_CASE(
    "the shipped displays: sRGB and Rec.1886 encode mid grey as their transfer functions, with exposure")
{
    io::ColorConfig config = shipped_config();
    io::DisplayConverter srgb(config, "", "");
    CHECK(srgb.display() == "sRGB");
    CHECK(srgb.view() == "Standard");
    CHECK(srgb.encoded_color_space() == "sRGB");
    std::vector<float> grey{static_cast<float>(srgb_to_linear(0.5)), 0.0f, 1.0f};
    srgb.apply(grey.data(), 1);
    CHECK(grey[0] == doctest::Approx(0.5).epsilon(1e-5));
    CHECK(grey[1] == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(grey[2] == doctest::Approx(1.0).epsilon(1e-5));
    io::DisplayConverter rec1886(config, "Rec.1886", "Standard", -1.0);
    std::vector<float> brighter{2.0f * static_cast<float>(std::pow(0.5, 2.4)), 0.0f, 0.0f};
    rec1886.apply(brighter.data(), 1);
    CHECK(brighter[0] == doctest::Approx(0.5).epsilon(1e-5));
}

TEST_CASE("the contact sheet goes through the display/view: linear 0.214 is byte 128 on sRGB")
{
    TempDir dir;
    io::ColorConfig config = shipped_config();
    std::vector<float> image(2 * 2 * 3, static_cast<float>(srgb_to_linear(128.0 / 255.0)));
    io::write_contact_sheet(dir.file("sheet.png"), 1, {{2, 2, image.data()}},
                            io::DisplayConverter(config, "", ""), 1);
    auto input = OIIO::ImageInput::open(dir.file("sheet.png"));
    REQUIRE(input);
    REQUIRE(input->spec().width == 4);
    std::vector<unsigned char> pixels(4 * 4 * 3);
    REQUIRE(input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
    CHECK(static_cast<int>(pixels[(1 * 4 + 1) * 3]) == 128); // inside the cell
    CHECK(static_cast<int>(pixels[0]) == 24);                // the border
    CHECK(input->spec().get_string_attribute("oiio:ColorSpace") == "sRGB");
}

TEST_CASE("converters are thread-safe: two threads give the serial result")
{
    io::ColorConfig config = shipped_config();
    io::ColorConverter srgb(config, "sRGB");
    std::vector<float> serial(3 * 4096);
    for (size_t i = 0; i < serial.size(); ++i)
        serial[i] = static_cast<float>(i % 977) / 600.0f;
    std::vector<float> a = serial, b = serial;
    srgb.to_scene_linear(serial.data(), serial.size() / 3);
    std::thread first([&] { srgb.to_scene_linear(a.data(), a.size() / 3); });
    std::thread second([&] { srgb.to_scene_linear(b.data(), b.size() / 3); });
    first.join();
    second.join();
    CHECK(a == serial);
    CHECK(b == serial);
}

TEST_CASE("config precedence: --ocio-config, then $OCIO, then the shipped config")
{
    REQUIRE_FALSE(io::shipped_color_config_path().empty());
    {
        ScopedOcioVariable unset(nullptr);
        io::ColorConfigLocation shipped = io::locate_color_config("");
        CHECK(shipped.source == io::ColorConfigSource::Shipped);
        CHECK(shipped.path == io::shipped_color_config_path());
    }
    ScopedOcioVariable from_environment("/studio/config.ocio");
    io::ColorConfigLocation environment = io::locate_color_config("");
    CHECK(environment.source == io::ColorConfigSource::Environment);
    CHECK(environment.path == "/studio/config.ocio");
    io::ColorConfigLocation explicit_file = io::locate_color_config("/show/config.ocio");
    CHECK(explicit_file.source == io::ColorConfigSource::CommandLine);
    CHECK(explicit_file.path == "/show/config.ocio");
}

TEST_CASE("unknown colour spaces, displays and views are usage errors that list what is available")
{
    io::ColorConfig config = shipped_config();
    auto expect_usage = [](const std::function<void()>& action, const std::vector<std::string>& mentions) {
        try {
            action();
            FAIL("no error");
        } catch (const Error& error) {
            CHECK(error.kind() == ErrorKind::Usage);
            for (const auto& mention : mentions)
                CHECK_MESSAGE(std::string(error.what()).find(mention) != std::string::npos, error.what());
        }
    };
    expect_usage([&] { config.find_color_space("nonsense", "--colorspace"); },
                 {"--colorspace 'nonsense'", "available: ", "ACEScg", "Gamma 2.4 Encoded Rec.709"});
    expect_usage([&] { io::ColorConverter(config, "nonsense"); }, {"available: "});
    expect_usage([&] { io::DisplayConverter(config, "P3", ""); }, {"--display 'P3'", "sRGB, Rec.1886"});
    expect_usage([&] { io::DisplayConverter(config, "sRGB", "Filmic"); },
                 {"--view 'Filmic'", "Standard, Raw"});
}

TEST_CASE("a broken or missing config file is a bad-input error naming the file and who chose it")
{
    TempDir dir;
    write_text(dir.file("broken.ocio"), "ocio_profile_version: 2\ncolorspaces: [this is: not, valid\n");
    write_text(dir.file("no_roles.ocio"), "ocio_profile_version: 2\nroles:\n  scene_linear: missing_space\n"
                                          "colorspaces:\n  - !<ColorSpace>\n    name: lin\n");
    for (const std::string& path :
         {dir.file("broken.ocio"), dir.file("no_roles.ocio"), dir.file("absent.ocio")}) {
        try {
            io::ColorConfig config({path, io::ColorConfigSource::Environment});
            FAIL("no error for " << path);
        } catch (const Error& error) {
            CHECK(error.kind() == ErrorKind::BadInput);
            CHECK(error.file() == path);
            CHECK_MESSAGE(std::string(error.what()).find("$OCIO") != std::string::npos, error.what());
        }
    }
}

TEST_CASE("the colour space an EXR records: chromaticities, else OpenEXR's scene-linear")
{
    TempDir dir;
    io::ColorConfig config = shipped_config();
    auto write = [&](const std::string& stem, const float* chromaticities) {
        const std::string name = stem + ".0001.exr";
        OIIO::ImageSpec spec(4, 3, 3, OIIO::TypeDesc::HALF);
        if (chromaticities)
            spec.attribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), chromaticities);
        std::vector<float> pixels(4 * 3 * 3, 0.5f);
        auto output = OIIO::ImageOutput::create(dir.file(name));
        REQUIRE(output->open(dir.file(name), spec));
        REQUIRE(output->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
        REQUIRE(output->close());
        io::SequenceReader reader(io::find_input_sequence(dir.file(stem + ".####.exr")), {});
        return io::recorded_color_space(reader, config);
    };
    io::RecordedColorSpace plain = write("plain", nullptr);
    CHECK(plain.space == "Linear Rec.709 (sRGB)");
    CHECK(plain.evidence == "OpenEXR default");
    const float ap1[8] = {0.713f, 0.293f, 0.165f, 0.830f, 0.128f, 0.044f, 0.32168f, 0.33767f};
    io::RecordedColorSpace acescg = write("acescg", ap1);
    CHECK(acescg.space == "ACEScg");
    CHECK(acescg.evidence == "chromaticities");
    const float p3[8] = {0.680f, 0.320f, 0.265f, 0.690f, 0.150f, 0.060f, 0.3127f, 0.3290f};
    CHECK_THROWS_WITH_AS(write("p3", p3), doctest::Contains("give --colorspace"), Error);
}
