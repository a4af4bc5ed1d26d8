// Benchmark data: a noisy RGB half-float ZIP EXR sequence of any size and length,
// made of a known low-rank signal plus per-frame noise, the way a cheap render of
// an animated shot looks to the denoiser. Used by bench/denoise.sh instead of the
// renderer because the benchmark needs 100 (and up to 800) frames of one plain
// RGB layer, while the built-in scenes have 48 frames of multi-layer AOVs.
//
// Signal: three smooth spatial modes with hard edges (a lit room-like gradient, a
// moving-light lobe, a box whose shading changes) times temporal weights that
// vary smoothly over the shot; noise: Gaussian with a standard deviation of
// `noise` × sqrt(signal) (shot-noise-like), plus rare fireflies. Every value
// comes from a hash of (seed, frame, pixel, channel), so the data are the same
// for any thread count.
//
//   bench_make_noisy_sequence --size 1920x1080 --frames 100 [--seed 1] [--noise 0.35]
//                             -o /tmp/noisy.%04d.exr
#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <Imath/half.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr double kTwoPi = 6.283185307179586;
// Probability that a sample is a firefly, and how much brighter it is.
constexpr double kFireflyProbability = 2e-6;
constexpr float kFireflyGain = 40.0f;

std::uint64_t mix(std::uint64_t value)
{
    value += 0x9e3779b97f4a7c15ull;
    value = (value ^ (value >> 30)) * 0xbf58476d1ce4e5b9ull;
    value = (value ^ (value >> 27)) * 0x94d049bb133111ebull;
    return value ^ (value >> 31);
}

double unit(std::uint64_t bits) { return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

struct Settings {
    int width = 1920;
    int height = 1080;
    int frames = 100;
    int first_frame = 1;
    std::uint64_t seed = 1;
    double noise = 0.35;
    std::string output;  // printf pattern with one %d-style field
};

[[noreturn]] void usage(const char* message)
{
    std::fprintf(stderr,
                 "bench_make_noisy_sequence: %s\nusage: bench_make_noisy_sequence --size WxH --frames N "
                 "[--first-frame N] [--seed S] [--noise X] -o name.%%04d.exr\n",
                 message);
    std::exit(2);
}

Settings parse(int argc, char** argv)
{
    Settings settings;
    for (int i = 1; i < argc; ++i) {
        std::string option = argv[i];
        if (i + 1 >= argc)
            usage(("missing value after " + option).c_str());
        const char* value = argv[++i];
        if (option == "--size") {
            if (std::sscanf(value, "%dx%d", &settings.width, &settings.height) != 2)
                usage("--size takes WIDTHxHEIGHT");
        } else if (option == "--frames") {
            settings.frames = std::atoi(value);
        } else if (option == "--first-frame") {
            settings.first_frame = std::atoi(value);
        } else if (option == "--seed") {
            settings.seed = std::strtoull(value, nullptr, 10);
        } else if (option == "--noise") {
            settings.noise = std::atof(value);
        } else if (option == "-o") {
            settings.output = value;
        } else {
            usage(("unknown option " + option).c_str());
        }
    }
    if (settings.output.empty() || settings.width < 1 || settings.height < 1 || settings.frames < 1)
        usage("need -o, a positive --size and --frames");
    return settings;
}

// The noise-free value of channel `c` at pixel (x, y) in frame `t` of `frames`.
float signal(int x, int y, int c, int t, int frames, int width, int height)
{
    double u = (x + 0.5) / width, v = (y + 0.5) / height;
    double phase = kTwoPi * t / frames;
    static const double kTint[3][3] = {{0.9, 0.8, 0.6}, {0.5, 0.6, 0.9}, {0.8, 0.3, 0.2}};
    // Mode 1: ambient room light, brighter towards the ceiling, red and green walls.
    double ambient = 0.25 + 0.35 * (1.0 - v);
    if (u < 0.12)
        ambient *= c == 0 ? 1.6 : 0.4;
    else if (u > 0.88)
        ambient *= c == 1 ? 1.6 : 0.4;
    // Mode 2: a lobe of light that sweeps across the room.
    double du = u - (0.5 + 0.3 * std::cos(phase)), dv = v - 0.45;
    double lobe = std::exp(-(du * du + dv * dv) * 12.0);
    // Mode 3: a box whose lit face changes (hard edges, the part blur would smear).
    bool in_box = u > 0.35 && u < 0.6 && v > 0.55 && v < 0.9;
    double box = in_box ? 0.6 : 0.0;
    double value = kTint[0][c] * ambient * (1.0 + 0.2 * std::sin(phase)) +
                   kTint[1][c] * lobe * (0.8 + 0.5 * std::sin(phase + 1.0)) +
                   kTint[2][c] * box * (0.5 + 0.45 * std::cos(2.0 * phase));
    return static_cast<float>(value);
}

void write_frame(const Settings& settings, int t)
{
    const int width = settings.width, height = settings.height;
    std::vector<Imath::half> pixels(static_cast<size_t>(width) * height * 3);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            for (int c = 0; c < 3; ++c) {
                size_t index = (static_cast<size_t>(y) * width + x) * 3 + c;
                float clean = signal(x, y, c, t, settings.frames, width, height);
                std::uint64_t key = mix(settings.seed ^ mix(static_cast<std::uint64_t>(t) ^ mix(index)));
                double u1 = unit(key), u2 = unit(mix(key)), u3 = unit(mix(key + 1));
                double gaussian = std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
                float value = clean + static_cast<float>(settings.noise * std::sqrt(clean) * gaussian);
                if (u3 < kFireflyProbability)
                    value = clean * kFireflyGain;
                pixels[index] = Imath::half(std::max(0.0f, value));
            }
        }
    }
    char path[4096];
    std::snprintf(path, sizeof path, settings.output.c_str(), settings.first_frame + t);
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeHalf);
    spec.channelnames = {"R", "G", "B"};
    spec.attribute("compression", "zip");
    auto output = OIIO::ImageOutput::create(path);
    if (!output || !output->open(path, spec) || !output->write_image(OIIO::TypeHalf, pixels.data()) ||
        !output->close()) {
        // Thrown, not exit(): exit() from a worker ran the static destructors
        // under the other workers, which crashed. parallel_for hands it to main.
        throw std::runtime_error(std::string("cannot write ") + path + ": " +
                                 (output ? output->geterror() : OIIO::geterror()));
    }
}

}  // namespace

int main(int argc, char** argv)
{
    Settings settings = parse(argc, argv);
    try {
        tbb::parallel_for(0, settings.frames, [&](int t) { write_frame(settings, t); });
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench_make_noisy_sequence: %s\n", error.what());
        return 1;
    }
    std::printf("wrote %d frames of %dx%d RGB half ZIP: %s\n", settings.frames, settings.width, settings.height,
                settings.output.c_str());
    return 0;
}
