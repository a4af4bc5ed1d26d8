// Fuzz harness: an image file through modestack's io layer, as `info` and the
// readers of every subcommand see it: `info`'s checks (chunk tables, every
// chunk decoded) and read_frame_header(), then the
// SequenceReader of a one-frame sequence (validation, layer selection), then
// every row read as float and in native types. The input is written to a
// temporary file first (the io layer opens files by name). Every rejection
// must be a modestack::Error (main() turns anything else into "internal error").
#include "core/common/error.h"
#include "io/frame_check.h"
#include "io/frame_header.h"
#include "io/sequence_reader.h"
#include "io/text_output.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

// Pixels actually decoded per input: a header may claim any size for free.
constexpr long long kMaxSamples = 1 << 20;
constexpr int kBandRows = 16;

const std::string& scratch_file()
{
    static const std::string path = [] {
        const char* directory = std::getenv("FUZZ_SCRATCH_DIR");
        if (!directory)
            directory = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        return std::string(directory) + "/modestack-fuzz-" + std::to_string(getpid()) + ".exr";
    }();
    return path;
}

void read_everything(const std::string& file)
{
    // `info`'s check of the chunk tables reads them from the untrusted bytes too.
    modestack::io::check_chunk_tables(file);
    modestack::io::FrameHeader header = modestack::io::read_frame_header(file);
    if (header.width <= 0 || header.height <= 0)
        return;
    modestack::io::FrameSequence sequence;
    sequence.pattern = file;
    sequence.printf_pattern = file;
    sequence.frames = {1};
    sequence.files = {file};
    modestack::io::SequenceReader reader(sequence, {});
    long long samples = static_cast<long long>(reader.width()) * reader.height() *
                        std::max<long long>(reader.selected_channel_count(), static_cast<long long>(header.channel_names.size()));
    if (samples > kMaxSamples)
        return;
    modestack::io::check_every_chunk(file);  // `info --check`
    std::vector<float> selected(static_cast<std::size_t>(reader.width()) * kBandRows * reader.selected_channel_count());
    std::vector<unsigned char> native;
    for (int row = 0; row < reader.height(); row += kBandRows) {
        int end = std::min(reader.height(), row + kBandRows);
        reader.read_selected(0, row, end, selected.data());
        reader.read_native(0, row, end, native);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static bool initialized = [] {
        modestack::io::set_io_threads(1);
        return true;
    }();
    (void)initialized;
    const std::string& file = scratch_file();
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    try {
        read_everything(file);
    } catch (const modestack::Error&) {
    }
    std::remove(file.c_str());
    return 0;
}
