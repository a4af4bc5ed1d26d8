// Progress reporting and cancellation for long loops. Core code calls
// Progress::advance() from any worker thread; one reporter prints to stderr:
// in place ("\r") on a terminal, a plain line every 10 % otherwise, nothing when
// quiet. The cancel flag is set by the app's signal handlers; long loops poll it.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

namespace modestack {

/// Thread-safe progress reporter for one phase of work at a time.
class Progress {
public:
    /// Reports to `stream`; `quiet` silences it; `in_place` redraws one line
    /// (use on a terminal) instead of printing a line per 10 %.
    Progress(std::FILE* stream, bool quiet, bool in_place);
    /// A reporter that prints nothing (for tests and library callers).
    static Progress& silent();

    /// Starts a phase named `phase` of `total` units of work.
    void begin(const std::string& phase, std::int64_t total);
    /// Adds `units` of finished work; safe to call from several threads.
    void advance(std::int64_t units = 1);
    /// Ends the phase and prints its elapsed time.
    void end();
    /// Prints a warning line (always, even when quiet: warnings matter).
    void warn(const std::string& message);

private:
    void draw(std::int64_t done, bool final_line);

    std::FILE* m_stream;
    bool m_quiet;
    bool m_in_place;
    std::mutex m_mutex;
    std::string m_phase;
    std::int64_t m_total = 0;
    std::atomic<std::int64_t> m_done{0};
    int m_last_decile = -1;
    int m_last_percent = -1;
    std::chrono::steady_clock::time_point m_start;
};

/// True once request_cancel_by_signal() was called.
bool cancel_requested();
/// Throws cancelled_error() when a cancel was requested; call between work units.
void throw_if_cancelled();
/// Signal number that caused the cancel request, or 0.
int cancel_signal();
/// Asks every long loop to stop at its next check and records the signal that
/// asked (async-signal-safe).
void request_cancel_by_signal(int signal_number);

}  // namespace modestack
