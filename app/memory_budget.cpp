#include "app/memory_budget.h"

#include "app/option_values.h"
#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <fstream>
#include <malloc.h>
#include <unistd.h>

namespace modestack::app {
namespace {

// The cgroup v2 memory limit of this process, or 0 when there is none.
std::int64_t cgroup_memory_limit()
{
    std::ifstream file("/sys/fs/cgroup/memory.max");
    std::string text;
    if (!(file >> text) || text == "max")
        return 0;
    try {
        return std::stoll(text);
    } catch (const std::exception&) {
        return 0;
    }
}

// Resident bytes of this process now (/proc/self/statm), or 0 when unknown.
std::int64_t resident_bytes()
{
    std::ifstream statm("/proc/self/statm");
    std::int64_t size = 0, resident = 0;
    if (!(statm >> size >> resident))
        return 0;
    return resident * sysconf(_SC_PAGE_SIZE);
}

// OpenEXR's buffers for one open file, without its worker threads: three chunks
// of scanlines, its line buffer and the codec's two (heaptrack of a 1080p run:
// allocated at open, resident once the file is read or written).
std::int64_t open_file_bytes(int width, std::size_t pixel_bytes, int chunk_rows)
{
    constexpr int kChunkBuffers = 3;
    return kChunkBuffers * static_cast<std::int64_t>(width) * static_cast<std::int64_t>(pixel_bytes) * chunk_rows;
}

}  // namespace

std::int64_t engine_memory_budget(std::int64_t max_memory_bytes, const io::SequenceReader& reader, int outputs,
                                  int extra_channels, const GuideFiles& guides)
{
    std::int64_t files = 0;
    for (int frame = 0; frame < reader.frame_count(); ++frame) {
        const std::size_t pixel = reader.native_pixel_bytes(frame);
        const int rows = reader.chunk_rows(frame);
        files += open_file_bytes(reader.width(), pixel, rows);
        if (frame < outputs)  // outputs add sigma channels in the first selected channel's type
            files += open_file_bytes(
                reader.width(), pixel + reader.selected_value_bytes(frame) * static_cast<std::size_t>(extra_channels),
                rows);
    }
    int open_files = reader.frame_count() + outputs;
    for (const io::SequenceReader* guide : guides.readers) {
        // The guide reads a few frames spread over the shot: count the largest files.
        std::vector<std::int64_t> sizes;
        for (int frame = 0; frame < guide->frame_count(); ++frame)
            sizes.push_back(
                open_file_bytes(guide->width(), guide->native_pixel_bytes(frame), guide->chunk_rows(frame)));
        const int read = std::min(guides.frames, guide->frame_count());
        std::partial_sort(sizes.begin(), sizes.begin() + read, sizes.end(), std::greater<>());
        for (int i = 0; i < read; ++i)
            files += sizes[static_cast<std::size_t>(i)];
        open_files += guide->frame_count();
    }
    const std::int64_t held = resident_bytes() + files;
    if (held >= max_memory_bytes)
        throw usage_error(fmt::format("--max-memory {} MiB is too small: the program and its {} open files alone "
                                      "hold about {} MiB",
                                      max_memory_bytes >> 20, open_files, (held >> 20) + 1));
    return max_memory_bytes - held;
}

std::int64_t automatic_memory_budget()
{
    std::int64_t physical = static_cast<std::int64_t>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
    std::int64_t limit = cgroup_memory_limit();
    std::int64_t available = limit > 0 && (physical <= 0 || limit < physical) ? limit : physical;
    return std::max<std::int64_t>(available / 4, std::int64_t(512) << 20);
}

std::int64_t parse_memory_budget(const std::string& text, const std::string& option)
{
    return text == "auto" ? automatic_memory_budget() : parse_memory_size(text, option);
}

void reuse_freed_memory()
{
    constexpr int kLargestReused = 32 << 20;  // glibc ignores larger thresholds
    mallopt(M_MMAP_THRESHOLD, kLargestReused);
    mallopt(M_TRIM_THRESHOLD, 2 * kLargestReused);
}

}  // namespace modestack::app
