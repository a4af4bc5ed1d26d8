#include "io/temporary_file.h"

#include <fmt/format.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <filesystem>
#include <mutex>
#include <string>
#include <set>
#include <system_error>
#include <unistd.h>

namespace modestack::io {
namespace {

namespace stdfs = std::filesystem;

constexpr const char* kSuffix = ".modestack-tmp";

const std::string& host_name()
{
    static const std::string name = [] {
        char buffer[256] = {};
        if (gethostname(buffer, sizeof buffer - 1) != 0 || buffer[0] == '\0')
            return std::string("localhost");
        std::string host(buffer);
        for (char& c : host)  // keep the name one path component
            if (c == '/')
                c = '_';
        return host;
    }();
    return name;
}

stdfs::path directory_of(const std::string& final_path)
{
    stdfs::path parent = stdfs::path(final_path).parent_path();
    return parent.empty() ? stdfs::path(".") : parent;
}

// The pid of a temporary `.<final>.<host>.<pid>-<n>.modestack-tmp` written on
// this host, or 0 when the name is not one (another host's, or not ours).
long local_owner(const std::string& name)
{
    const std::string suffix = kSuffix;
    if (name.size() <= suffix.size() + 1 || name[0] != '.' ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return 0;
    std::string stem = name.substr(0, name.size() - suffix.size());  // .<final>.<host>.<pid>-<n>
    size_t dot = stem.rfind('.');
    if (dot == std::string::npos)
        return 0;
    std::string id = stem.substr(dot + 1);  // <pid>-<n>
    std::string before = stem.substr(0, dot);
    const std::string host = "." + host_name();
    if (before.size() <= host.size() || before.compare(before.size() - host.size(), host.size(), host) != 0)
        return 0;
    size_t dash = id.find('-');
    auto all_digits = [](const std::string& text) {
        return !text.empty() && text.size() <= 9 &&
               text.find_first_not_of("0123456789") == std::string::npos;
    };
    if (dash == std::string::npos || !all_digits(id.substr(0, dash)) || !all_digits(id.substr(dash + 1)))
        return 0;
    return std::stol(id.substr(0, dash));
}

bool process_is_gone(long pid)
{
    return pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

}  // namespace

std::string temporary_path_for(const std::string& final_path)
{
    static std::atomic<int> counter{0};
    std::string name = fmt::format(".{}.{}.{}-{}{}", stdfs::path(final_path).filename().string(), host_name(),
                                   getpid(), counter++, kSuffix);
    return (stdfs::path(final_path).parent_path() / name).string();
}

int remove_stale_temporaries(const std::string& final_path)
{
    static std::mutex mutex;
    static std::set<std::string> cleaned;
    std::error_code error;
    stdfs::path directory = stdfs::absolute(directory_of(final_path), error);
    if (error)
        return 0;
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (!cleaned.insert(directory.lexically_normal().string()).second)
            return 0;
    }
    int removed = 0;
    // A directory that does not exist yet has nothing to clean; errors end the walk quietly.
    for (stdfs::directory_iterator entry(directory, error), end; !error && entry != end; entry.increment(error)) {
        std::error_code ignored;
        if (process_is_gone(local_owner(entry->path().filename().string())) && stdfs::remove(entry->path(), ignored))
            ++removed;
    }
    return removed;
}

}  // namespace modestack::io
