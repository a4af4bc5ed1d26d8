#include "app/memory_budget.h"

#include "app/option_values.h"

#include <algorithm>
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

}  // namespace

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
