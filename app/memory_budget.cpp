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

}  // namespace

std::int64_t engine_memory_budget(std::int64_t max_memory_bytes, const io::SequenceReader& reader,
                                  std::int64_t output_bytes, const GuideFiles& guides)
{
    std::int64_t files = output_bytes;
    int input_files = reader.frame_count();
    for (int frame = 0; frame < reader.frame_count(); ++frame)
        files += reader.decoder_buffer_bytes(frame);
    for (const io::SequenceReader* guide : guides.readers) {
        // The guide reads a few frames spread over the shot: count the largest files.
        std::vector<std::int64_t> sizes;
        for (int frame = 0; frame < guide->frame_count(); ++frame)
            sizes.push_back(guide->decoder_buffer_bytes(frame));
        const int read = std::min(guides.frames, guide->frame_count());
        std::partial_sort(sizes.begin(), sizes.begin() + read, sizes.end(), std::greater<>());
        for (int i = 0; i < read; ++i)
            files += sizes[static_cast<std::size_t>(i)];
        input_files += guide->frame_count();
    }
    const std::int64_t held = resident_bytes() + files;
    if (held >= max_memory_bytes)
        throw usage_error(fmt::format("--max-memory {} MiB is too small: the program, its {} input files and "
                                      "the outputs' buffers alone hold about {} MiB",
                                      max_memory_bytes >> 20, input_files, (held >> 20) + 1));
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
