// The I/O floor of `modestack denoise`: the time OpenImageIO alone needs to read
// every channel of every input frame and write each frame back with the same
// channels, pixel types and compression plus the extra channels our output adds
// (`sigma.R/G/B`, in the pixel type of the first channel), in scanline order. No
// math: whatever modestack spends beyond this is its own overhead.
//
// Frames run in parallel on the TBB arena (as modestack reads and writes the
// frames of a band in parallel), each frame read and written band by band.
// OIIO's and OpenEXR's own thread pools keep their defaults (all cores), as in
// modestack with --threads 0.
//
// What is written matters, because ZIP's speed depends on the data: by default
// the input's channels are copied and the appended channels hold 0.1 × |R|, |G|,
// |B| (noise-like, slower to compress than modestack's smooth denoised values
// and sigma). With CONTENT_PATTERN, every output pixel is taken from those frames
// instead (e.g. a previous `modestack denoise` output: same channels and types),
// loaded into memory before the clock starts, so the floor writes exactly the
// bytes modestack writes while still decoding every input frame.
//
//   bench_io_floor IN_PATTERN OUT_PATTERN FIRST_FRAME COUNT [BAND_ROWS] [EXTRA_CHANNELS] [CONTENT_PATTERN]
//   (patterns are printf patterns, e.g. /tmp/noisy.%04d.exr)
#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <Imath/half.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

std::string frame_path(const char* pattern, int frame)
{
    char path[4096];
    std::snprintf(path, sizeof path, pattern, frame);
    return path;
}

// Every pixel of a frame in its native channel types, packed per pixel.
std::vector<unsigned char> load_native(const std::string& path)
{
    auto input = OIIO::ImageInput::open(path);
    std::vector<unsigned char> pixels;
    if (!input) {
        std::fprintf(stderr, "bench_io_floor: %s: %s\n", path.c_str(), OIIO::geterror().c_str());
        return pixels;
    }
    const OIIO::ImageSpec& spec = input->spec();
    pixels.resize(spec.image_bytes(true));
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeUnknown, pixels.data()))
        pixels.clear();
    return pixels;
}

// Copies one frame in bands of `band_rows` scanlines; with `content`, writes its
// pixels instead of the copied input plus synthesized channels. False on error.
bool copy_frame(const std::string& input_path, const std::string& output_path, int band_rows, int extra_count,
                const std::vector<unsigned char>* content)
{
    auto input = OIIO::ImageInput::open(input_path);
    if (!input) {
        std::fprintf(stderr, "bench_io_floor: %s: %s\n", input_path.c_str(), OIIO::geterror().c_str());
        return false;
    }
    const OIIO::ImageSpec& in_spec = input->spec();
    OIIO::ImageSpec out_spec = in_spec;
    if (out_spec.channelformats.empty())
        out_spec.channelformats.assign(out_spec.nchannels, out_spec.format);
    const OIIO::TypeDesc extra_type = out_spec.channelformats[0];
    static const char* kExtraNames[] = {"sigma.R", "sigma.G", "sigma.B", "sigma.A"};
    for (int k = 0; k < extra_count; ++k) {
        out_spec.channelnames.push_back(kExtraNames[k % 4]);
        out_spec.channelformats.push_back(extra_type);
    }
    out_spec.nchannels = static_cast<int>(out_spec.channelnames.size());
    out_spec.tile_width = out_spec.tile_height = out_spec.tile_depth = 0;
    out_spec.erase_attribute("openexr:lineOrder");

    size_t in_pixel_bytes = 0;
    std::vector<size_t> offsets;
    for (int c = 0; c < in_spec.nchannels; ++c) {
        offsets.push_back(in_pixel_bytes);
        in_pixel_bytes += in_spec.channelformat(c).size();
    }
    size_t out_pixel_bytes = in_pixel_bytes + extra_count * extra_type.size();
    size_t frame_bytes = static_cast<size_t>(in_spec.width) * in_spec.height * out_pixel_bytes;
    if (content && content->size() != frame_bytes) {
        std::fprintf(stderr, "bench_io_floor: content frame has %zu bytes, the output %zu\n", content->size(),
                     frame_bytes);
        return false;
    }
    bool half_source = in_spec.channelformat(0) == OIIO::TypeHalf && extra_type == OIIO::TypeHalf;

    auto output = OIIO::ImageOutput::create(output_path);
    if (!output || !output->open(output_path, out_spec)) {
        std::fprintf(stderr, "bench_io_floor: %s: %s\n", output_path.c_str(),
                     output ? output->geterror().c_str() : OIIO::geterror().c_str());
        return false;
    }
    std::vector<unsigned char> in_rows, out_rows;
    for (int row = 0; row < in_spec.height; row += band_rows) {
        int end = std::min(in_spec.height, row + band_rows);
        size_t pixels = static_cast<size_t>(in_spec.width) * (end - row);
        in_rows.resize(pixels * in_pixel_bytes);
        out_rows.resize(pixels * out_pixel_bytes);
        if (!input->read_scanlines(0, 0, in_spec.y + row, in_spec.y + end, in_spec.z, 0, in_spec.nchannels,
                                   OIIO::TypeUnknown, in_rows.data())) {
            std::fprintf(stderr, "bench_io_floor: %s: %s\n", input_path.c_str(), input->geterror().c_str());
            return false;
        }
        if (content) {
            std::memcpy(out_rows.data(), content->data() + static_cast<size_t>(row) * in_spec.width * out_pixel_bytes,
                        pixels * out_pixel_bytes);
        }
        for (size_t p = 0; !content && p < pixels; ++p) {
            const unsigned char* source = in_rows.data() + p * in_pixel_bytes;
            unsigned char* target = out_rows.data() + p * out_pixel_bytes;
            std::memcpy(target, source, in_pixel_bytes);
            unsigned char* tail = target + in_pixel_bytes;
            for (int k = 0; k < extra_count; ++k) {
                int channel = std::min(k, in_spec.nchannels - 1);
                float value = 0.0f;
                if (half_source) {
                    Imath::half h;
                    std::memcpy(&h, source + offsets[channel], sizeof h);
                    value = 0.1f * std::fabs(static_cast<float>(h));
                    Imath::half out(value);
                    std::memcpy(tail, &out, sizeof out);
                } else {
                    OIIO::convert_pixel_values(in_spec.channelformat(channel), source + offsets[channel],
                                               OIIO::TypeFloat, &value, 1);
                    value = 0.1f * std::fabs(value);
                    OIIO::convert_pixel_values(OIIO::TypeFloat, &value, extra_type, tail, 1);
                }
                tail += extra_type.size();
            }
        }
        if (!output->write_scanlines(out_spec.y + row, out_spec.y + end, out_spec.z, OIIO::TypeUnknown,
                                     out_rows.data())) {
            std::fprintf(stderr, "bench_io_floor: %s: %s\n", output_path.c_str(), output->geterror().c_str());
            return false;
        }
    }
    return output->close();
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 5) {
        std::fprintf(stderr,
                     "usage: bench_io_floor IN_PATTERN OUT_PATTERN FIRST_FRAME COUNT [BAND_ROWS=64] "
                     "[EXTRA_CHANNELS=3] [CONTENT_PATTERN]\n");
        return 2;
    }
    const char* in_pattern = argv[1];
    const char* out_pattern = argv[2];
    int first = std::atoi(argv[3]), count = std::atoi(argv[4]);
    int band_rows = argc > 5 ? std::atoi(argv[5]) : 64;
    int extra_count = argc > 6 ? std::atoi(argv[6]) : 3;
    if (count < 1 || band_rows < 1 || extra_count < 0) {
        std::fprintf(stderr, "bench_io_floor: COUNT and BAND_ROWS must be positive\n");
        return 2;
    }
    std::atomic<bool> failed{false};
    std::vector<std::vector<unsigned char>> content;
    if (argc > 7) {
        content.resize(count);
        tbb::parallel_for(0, count, [&](int i) {
            content[i] = load_native(frame_path(argv[7], first + i));
            if (content[i].empty())
                failed = true;
        });
        if (failed)
            return 1;
    }
    auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(0, count, [&](int i) {
        if (!copy_frame(frame_path(in_pattern, first + i), frame_path(out_pattern, first + i), band_rows, extra_count,
                        content.empty() ? nullptr : &content[i]))
            failed = true;
    });
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("{\"frames\": %d, \"band_rows\": %d, \"extra_channels\": %d, \"content\": %s, \"seconds\": %.3f}\n",
                count, band_rows, extra_count, content.empty() ? "false" : "true", seconds);
    return failed ? 1 : 0;
}
