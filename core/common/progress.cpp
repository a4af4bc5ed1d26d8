#include "core/common/progress.h"

#include "core/common/error.h"

#include <algorithm>

namespace modestack {
namespace {
std::atomic<bool> g_cancel{false};
std::atomic<int> g_cancel_signal{0};
}  // namespace

Progress::Progress(std::FILE* stream, bool quiet, bool in_place)
    : m_stream(stream), m_quiet(quiet || stream == nullptr), m_in_place(in_place)
{
}

Progress& Progress::silent()
{
    static Progress nothing(nullptr, true, false);
    return nothing;
}

void Progress::begin(const std::string& phase, std::int64_t total)
{
    std::lock_guard<std::mutex> lock(m_mutex);
    m_phase = phase;
    m_total = total > 0 ? total : 1;
    m_done = 0;
    m_last_decile = -1;
    m_last_percent = -1;
    m_start = std::chrono::steady_clock::now();
    draw(0, false);
}

void Progress::advance(std::int64_t units)
{
    std::int64_t done = m_done.fetch_add(units) + units;
    if (m_quiet)
        return;
    std::lock_guard<std::mutex> lock(m_mutex);
    draw(done, false);
}

void Progress::end()
{
    std::lock_guard<std::mutex> lock(m_mutex);
    draw(m_total, true);
}

void Progress::warn(const std::string& message)
{
    if (m_stream == nullptr)
        return;
    std::lock_guard<std::mutex> lock(m_mutex);
    std::fprintf(m_stream, "%smodestack: warning: %s\n", m_in_place ? "\r\033[K" : "",
                 message.c_str());
    std::fflush(m_stream);
}

// Caller holds m_mutex.
void Progress::draw(std::int64_t done, bool final_line)
{
    if (m_quiet)
        return;
    int percent = static_cast<int>(100 * std::min(done, m_total) / m_total);
    if (final_line) {
        double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
        std::fprintf(m_stream, "%s%s: done in %.2f s\n", m_in_place ? "\r\033[K" : "", m_phase.c_str(),
                     seconds);
    } else if (m_in_place) {
        if (percent == m_last_percent)
            return;
        m_last_percent = percent;
        std::fprintf(m_stream, "\r\033[K%s: %3d%%", m_phase.c_str(), percent);
    } else {
        int decile = percent / 10;
        if (decile == m_last_decile)
            return;
        m_last_decile = decile;
        std::fprintf(m_stream, "%s: %d%%\n", m_phase.c_str(), decile * 10);
    }
    std::fflush(m_stream);
}

bool cancel_requested() { return g_cancel.load(std::memory_order_relaxed); }
void throw_if_cancelled()
{
    if (cancel_requested())
        throw cancelled_error();
}
int cancel_signal() { return g_cancel_signal.load(); }
void request_cancel_by_signal(int signal_number)
{
    g_cancel_signal.store(signal_number);
    g_cancel.store(true);
}

}  // namespace modestack
