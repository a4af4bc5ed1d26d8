// A headless Chromium driven over the DevTools protocol on a pipe
// (--remote-debugging-pipe: the browser reads NUL-terminated JSON messages on
// its fd 3 and writes them on fd 4), for the report's browser test. No node,
// no python: the commands are the few the test needs. The browser runs in its
// own process group and is killed with it when this object dies.
#pragma once

#include <nlohmann/json.hpp>

#include <chrono>
#include <string>
#include <vector>

namespace modestack::browser {

/// The installed Chromium ($MODESTACK_CHROMIUM, else chromium or chromium-browser on the
/// usual paths), or "" when there is none.
std::string find_chromium();

/// A running headless browser with one page attached.
class DevToolsPipe {
public:
    /// Starts `chromium` with a `width` × `height` window and attaches to its page.
    /// Throws std::runtime_error when it does not answer.
    DevToolsPipe(const std::string& chromium, int width, int height);
    ~DevToolsPipe();
    DevToolsPipe(const DevToolsPipe&) = delete;
    DevToolsPipe& operator=(const DevToolsPipe&) = delete;

    /// Sends `method` to the page and returns its result; throws on a protocol error
    /// or when no answer comes within `timeout`.
    nlohmann::json page(const std::string& method, const nlohmann::json& params = nlohmann::json::object(),
                        std::chrono::milliseconds timeout = std::chrono::milliseconds(10000));
    /// Evaluates `expression` in the page (promises awaited) and returns its value.
    nlohmann::json evaluate(const std::string& expression);
    /// Waits for the page event `method` (already seen ones count).
    void wait_for_event(const std::string& method, std::chrono::milliseconds timeout);
    /// Errors the page reported: exceptions, console.error/assert, error log entries.
    const std::vector<std::string>& page_errors() const { return m_errors; }

private:
    nlohmann::json call(const std::string& method, const nlohmann::json& params, const std::string& session,
                        std::chrono::milliseconds timeout);
    bool read_message(nlohmann::json& message, std::chrono::steady_clock::time_point deadline);
    void note_event(const nlohmann::json& message);

    int m_pid = -1;
    int m_write_fd = -1;
    int m_read_fd = -1;
    int m_next_id = 1;
    std::string m_session;
    std::string m_buffer;
    std::string m_profile;
    std::vector<std::string> m_events;
    std::vector<std::string> m_errors;
};

}  // namespace modestack::browser
