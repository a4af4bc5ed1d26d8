// The working-memory budget of `denoise --max-memory`: a size, or "auto" for a
// share of what this machine (or the container's memory limit) has, so that a
// shot which fits is read once and kept, while a farm node running several jobs
// still has room for them.
#pragma once

#include <cstdint>
#include <string>

namespace modestack::app {

/// A quarter of the physical memory, or of the cgroup's memory.max when that is
/// smaller (containers, farm slots); at least 512 MiB.
std::int64_t automatic_memory_budget();

/// "auto" → automatic_memory_budget(); otherwise parse_memory_size(text, option).
std::int64_t parse_memory_budget(const std::string& text, const std::string& option);

}  // namespace modestack::app
