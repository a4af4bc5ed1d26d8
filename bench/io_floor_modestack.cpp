// The I/O floor of `modestack denoise` through modestack's own I/O layer: the
// same work as bench_io_floor (decode every channel of every input frame, write
// each frame with the extra sigma channels, frames in parallel on TBB, band by
// band), but reading with io::SequenceReader and writing with io::FrameOutput,
// whose ZIP outputs are compressed with libdeflate, not OpenImageIO's zlib. The
// pixels written are those of CONTENT_PATTERN (a previous `modestack denoise`
// output: the selected channels, then `<layer>.sigma.*`), loaded as float
// before the clock starts, as the denoiser holds them. The gap between this and
// bench_io_floor is what the faster codec saves; the gap between this and
// `modestack denoise` is the denoiser's own work.
//
//   bench_io_floor_modestack IN_PATTERN OUT_PATTERN FIRST_FRAME COUNT BAND_ROWS CONTENT_PATTERN
#include "io/frame_output.h"
#include "io/sequence.h"
#include "io/sequence_reader.h"

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

using namespace modestack;

namespace {

std::string frame_path(const char* pattern, int frame)
{
    char path[4096];
    std::snprintf(path, sizeof path, pattern, frame);
    return path;
}

// The named channels of an EXR as float, interleaved; empty on failure.
std::vector<float> load_channels(const std::string& path, const std::vector<std::string>& names)
{
    auto input = OIIO::ImageInput::open(path);
    if (!input)
        return {};
    const OIIO::ImageSpec& spec = input->spec();
    std::vector<float> all(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, all.data()))
        return {};
    std::vector<int> indices;
    for (const std::string& name : names) {
        indices.push_back(spec.channelindex(name));
        if (indices.back() < 0)
            return {};
    }
    std::vector<float> picked;
    picked.reserve(static_cast<size_t>(spec.width) * spec.height * names.size());
    for (size_t p = 0; p < static_cast<size_t>(spec.width) * spec.height; ++p)
        for (int index : indices)
            picked.push_back(all[p * spec.nchannels + index]);
    return picked;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 7) {
        std::fprintf(stderr, "usage: bench_io_floor_modestack IN_PATTERN OUT_PATTERN FIRST_FRAME COUNT BAND_ROWS "
                             "CONTENT_PATTERN\n");
        return 2;
    }
    const char* out_pattern = argv[2];
    const int first = std::atoi(argv[3]), count = std::atoi(argv[4]), band_rows = std::atoi(argv[5]);
    if (count < 1 || band_rows < 1) {
        std::fprintf(stderr, "bench_io_floor_modestack: COUNT and BAND_ROWS must be positive\n");
        return 2;
    }
    try {
        io::SequenceReader reader(io::find_input_sequence(argv[1]), {});
        const std::vector<std::string> selected = reader.selected_channel_names();
        std::vector<std::string> sigma_names;  // as modestack denoise names them
        for (const io::SelectedLayer& layer : reader.layers())
            sigma_names.insert(sigma_names.end(), layer.sigma_names.begin(), layer.sigma_names.end());
        std::vector<std::string> content_names = selected;
        content_names.insert(content_names.end(), sigma_names.begin(), sigma_names.end());
        std::vector<std::vector<float>> content(count);
        std::atomic<bool> failed{false};
        tbb::parallel_for(0, count, [&](int i) {
            content[i] = load_channels(frame_path(argv[6], first + i), content_names);
            if (content[i].empty())
                failed = true;
        });
        if (failed) {
            std::fprintf(stderr, "bench_io_floor_modestack: cannot read the content frames\n");
            return 1;
        }
        const int width = reader.width(), height = reader.height();
        const size_t channels = selected.size();
        const auto start = std::chrono::steady_clock::now();
        tbb::parallel_for(0, count, [&](int i) {
            io::FrameOutput output(frame_path(out_pattern, first + i), reader, i, sigma_names, {});
            std::vector<unsigned char> native;
            std::vector<float> replaced, sigma;
            for (int row = 0; row < height; row += band_rows) {
                const int end = std::min(height, row + band_rows);
                const size_t pixels = static_cast<size_t>(width) * (end - row);
                reader.read_native(i, row, end, native);  // every input frame is decoded, as denoise does
                const float* source = content[i].data() + static_cast<size_t>(row) * width * 2 * channels;
                replaced.resize(pixels * channels);
                sigma.resize(pixels * channels);
                for (size_t p = 0; p < pixels; ++p)
                    for (size_t c = 0; c < channels; ++c) {
                        replaced[p * channels + c] = source[p * 2 * channels + c];
                        sigma[p * channels + c] = source[p * 2 * channels + channels + c];
                    }
                output.write_replaced_rows(row, end, native, replaced.data(), sigma.data());
            }
            output.commit();
        });
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("{\"frames\": %d, \"band_rows\": %d, \"writer\": \"modestack\", \"seconds\": %.3f}\n", count,
                    band_rows, seconds);
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench_io_floor_modestack: %s\n", error.what());
        return 1;
    }
    return 0;
}
