// Test-only, preloaded into `modestack` (LD_PRELOAD) by the interruption tests:
// holds a run at a chosen call until the test has signalled it, so that the
// signal always lands while the run is writing, however fast the machine.
// PAUSE_HOOK_AT names the call, "rename:2" (after the second rename: a render
// has committed two frames) or "libdeflate_zlib_compress:1" (before the first
// ZIP chunk of a denoise's outputs: every temporary file is open); at it the
// hook creates PAUSE_HOOK_DIR/paused, then waits until PAUSE_HOOK_DIR/resume
// exists and no signal is pending for the process (its handler has run), and
// goes on. Built without the project's compile and link options (no sanitizer:
// it must not come before a sanitized binary's runtime).
#include <libdeflate.h>

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>

namespace {

std::atomic<int> g_calls{0};

// Counts a call of `function`; true for the one PAUSE_HOOK_AT names.
bool is_pause_call(const char* function)
{
    const char* at = std::getenv("PAUSE_HOOK_AT");
    const char* colon = at ? std::strrchr(at, ':') : nullptr;
    if (!colon || std::string(at, colon) != function)
        return false;
    return ++g_calls == std::atoi(colon + 1);
}

// True while a signal sent to the process waits for a thread to handle it.
bool signal_pending()
{
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("ShdPnd:", 0) == 0)
            return line.find_first_not_of("0 \t", 7) != std::string::npos;
    return false;
}

void pause_here()
{
    const char* directory = std::getenv("PAUSE_HOOK_DIR");
    if (!directory)
        return;
    const std::string resume = std::string(directory) + "/resume";
    std::ofstream(std::string(directory) + "/paused");
    // Two minutes at most: a test that died must not leave a process waiting for ever.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
    while ((access(resume.c_str(), F_OK) != 0 || signal_pending()) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

template <typename Function>
Function next_definition(const char* name)
{
    return reinterpret_cast<Function>(dlsym(RTLD_NEXT, name));
}

}  // namespace

extern "C" int rename(const char* from, const char* to)
{
    static const auto real = next_definition<int (*)(const char*, const char*)>("rename");
    const int result = real(from, to);
    if (is_pause_call("rename"))
        pause_here();
    return result;
}

extern "C" size_t libdeflate_zlib_compress(libdeflate_compressor* compressor, const void* in, size_t in_bytes,
                                           void* out, size_t out_bytes_available)
{
    static const auto real = next_definition<decltype(&libdeflate_zlib_compress)>("libdeflate_zlib_compress");
    if (is_pause_call("libdeflate_zlib_compress"))
        pause_here();
    return real(compressor, in, in_bytes, out, out_bytes_available);
}
