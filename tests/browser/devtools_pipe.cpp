#include "tests/browser/devtools_pipe.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace modestack::browser {
namespace {

using Clock = std::chrono::steady_clock;

void write_all(int fd, const std::string& bytes)
{
    size_t written = 0;
    while (written < bytes.size()) {
        ssize_t count = ::write(fd, bytes.data() + written, bytes.size() - written);
        if (count < 0 && errno == EINTR)
            continue;
        if (count <= 0)
            throw std::runtime_error("the browser closed its DevTools pipe");
        written += static_cast<size_t>(count);
    }
}

}  // namespace

std::string find_chromium()
{
    if (const char* chosen = std::getenv("MODESTACK_CHROMIUM"))
        return access(chosen, X_OK) == 0 ? chosen : "";
    for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser"})
        if (access(path, X_OK) == 0)
            return path;
    return "";
}

DevToolsPipe::DevToolsPipe(const std::string& chromium, int width, int height)
{
    int to_browser[2], from_browser[2];
    if (pipe(to_browser) != 0 || pipe(from_browser) != 0)
        throw std::runtime_error("cannot make the DevTools pipes");
    char profile[] = "/tmp/modestack-chromium-XXXXXX";
    if (!mkdtemp(profile))
        throw std::runtime_error("cannot make a browser profile directory");
    m_profile = profile;
    std::string window = "--window-size=" + std::to_string(width) + "," + std::to_string(height);
    std::string user_data = "--user-data-dir=" + m_profile;
    m_pid = fork();
    if (m_pid < 0)
        throw std::runtime_error("cannot start the browser");
    if (m_pid == 0) {
        setpgid(0, 0);
        // Move both ends out of the way first: a pipe end may already be fd 3 or 4.
        int reading = fcntl(to_browser[0], F_DUPFD, 10), writing = fcntl(from_browser[1], F_DUPFD, 10);
        dup2(reading, 3);
        dup2(writing, 4);
        int null = open("/dev/null", O_RDWR);
        dup2(null, 0);
        dup2(null, 1);
        dup2(null, 2);
        for (int fd = 5; fd < 1024; ++fd)
            close(fd);
        execl(chromium.c_str(), chromium.c_str(), "--headless=new", "--no-sandbox", "--disable-gpu",
              "--remote-debugging-pipe", "--no-first-run", "--no-default-browser-check", "--hide-scrollbars",
              "--disable-extensions", "--mute-audio", window.c_str(), user_data.c_str(), "about:blank",
              static_cast<char*>(nullptr));
        _exit(127);
    }
    setpgid(m_pid, m_pid);
    close(to_browser[0]);
    close(from_browser[1]);
    m_write_fd = to_browser[1];
    m_read_fd = from_browser[0];

    nlohmann::json targets = call("Target.getTargets", nlohmann::json::object(), "", std::chrono::seconds(20));
    std::string target;
    for (const auto& info : targets["targetInfos"])
        if (info["type"] == "page")
            target = info["targetId"];
    if (target.empty())
        target = call("Target.createTarget", {{"url", "about:blank"}}, "", std::chrono::seconds(10))["targetId"];
    m_session = call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}}, "", std::chrono::seconds(10))
                    ["sessionId"];
    page("Runtime.enable");
    page("Log.enable");
    page("Page.enable");
    page("Emulation.setDeviceMetricsOverride",
         {{"width", width}, {"height", height}, {"deviceScaleFactor", 1}, {"mobile", false}});
}

DevToolsPipe::~DevToolsPipe()
{
    if (m_pid > 0) {
        try {
            nlohmann::json close{{"id", m_next_id++}, {"method", "Browser.close"}};
            write_all(m_write_fd, close.dump() + std::string(1, '\0'));
        } catch (const std::exception&) {
        }
        // A second to close by itself, then the whole process group goes.
        auto deadline = Clock::now() + std::chrono::seconds(1);
        int status = 0;
        while (waitpid(m_pid, &status, WNOHANG) == 0 && Clock::now() < deadline)
            usleep(20000);
        kill(-m_pid, SIGKILL);
        waitpid(m_pid, &status, WNOHANG);
    }
    if (m_write_fd >= 0)
        close(m_write_fd);
    if (m_read_fd >= 0)
        close(m_read_fd);
    std::error_code error;
    if (!m_profile.empty())
        std::filesystem::remove_all(m_profile, error);
}

bool DevToolsPipe::read_message(nlohmann::json& message, Clock::time_point deadline)
{
    for (;;) {
        size_t end = m_buffer.find('\0');
        if (end != std::string::npos) {
            message = nlohmann::json::parse(m_buffer.substr(0, end));
            m_buffer.erase(0, end + 1);
            return true;
        }
        auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
        if (left <= 0)
            return false;
        pollfd ready{m_read_fd, POLLIN, 0};
        int polled = poll(&ready, 1, static_cast<int>(left));
        if (polled < 0 && errno == EINTR)
            continue;
        if (polled <= 0)
            return false;
        char chunk[65536];
        ssize_t count = ::read(m_read_fd, chunk, sizeof(chunk));
        if (count <= 0)
            throw std::runtime_error("the browser closed its DevTools pipe");
        m_buffer.append(chunk, static_cast<size_t>(count));
    }
}

void DevToolsPipe::note_event(const nlohmann::json& message)
{
    const std::string method = message.value("method", "");
    m_events.push_back(method);
    const nlohmann::json& params = message["params"];
    if (method == "Runtime.exceptionThrown")
        m_errors.push_back("exception: " + params["exceptionDetails"].dump());
    else if (method == "Runtime.consoleAPICalled" && (params["type"] == "error" || params["type"] == "assert"))
        m_errors.push_back("console." + params["type"].get<std::string>() + ": " + params["args"].dump());
    else if (method == "Log.entryAdded" && params["entry"]["level"] == "error")
        m_errors.push_back("log: " + params["entry"].value("text", "") + " " + params["entry"].value("url", ""));
}

nlohmann::json DevToolsPipe::call(const std::string& method, const nlohmann::json& params, const std::string& session,
                                  std::chrono::milliseconds timeout)
{
    const int id = m_next_id++;
    nlohmann::json request{{"id", id}, {"method", method}, {"params", params}};
    if (!session.empty())
        request["sessionId"] = session;
    write_all(m_write_fd, request.dump() + std::string(1, '\0'));
    const auto deadline = Clock::now() + timeout;
    nlohmann::json message;
    while (read_message(message, deadline)) {
        if (message.contains("method")) {
            note_event(message);
            continue;
        }
        if (message.value("id", -1) != id)
            continue;
        if (message.contains("error"))
            throw std::runtime_error(method + " failed: " + message["error"].dump());
        return message["result"];
    }
    throw std::runtime_error(method + ": no answer from the browser in time");
}

nlohmann::json DevToolsPipe::page(const std::string& method, const nlohmann::json& params,
                                  std::chrono::milliseconds timeout)
{
    return call(method, params, m_session, timeout);
}

nlohmann::json DevToolsPipe::evaluate(const std::string& expression)
{
    nlohmann::json result =
        page("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}});
    if (result.contains("exceptionDetails"))
        throw std::runtime_error("evaluating '" + expression + "' threw " + result["exceptionDetails"].dump());
    return result["result"].value("value", nlohmann::json());
}

void DevToolsPipe::wait_for_event(const std::string& method, std::chrono::milliseconds timeout)
{
    const auto deadline = Clock::now() + timeout;
    nlohmann::json message;
    while (std::find(m_events.begin(), m_events.end(), method) == m_events.end()) {
        if (!read_message(message, deadline))
            throw std::runtime_error("no " + method + " from the browser in time");
        if (message.contains("method"))
            note_event(message);
    }
}

}  // namespace modestack::browser
