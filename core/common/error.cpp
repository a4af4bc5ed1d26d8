#include "core/common/error.h"

#include <algorithm>

namespace modestack {
namespace {

// Keep what() on one line whatever a library put in the reason.
std::string one_line(std::string text)
{
    std::replace(text.begin(), text.end(), '\n', ' ');
    std::replace(text.begin(), text.end(), '\r', ' ');
    while (!text.empty() && text.back() == ' ')
        text.pop_back();
    return text;
}

std::string compose(const std::string& reason, const std::string& file)
{
    return one_line(file.empty() ? reason : file + ": " + reason);
}

}  // namespace

Error::Error(ErrorKind kind, const std::string& reason, const std::string& file, int frame)
    : std::runtime_error(compose(reason, file)), m_kind(kind), m_file(file), m_frame(frame)
{
}

Error bad_input(const std::string& file, const std::string& reason)
{
    return Error(ErrorKind::BadInput, reason, file);
}

Error usage_error(const std::string& reason) { return Error(ErrorKind::Usage, reason); }

Error cancelled_error() { return Error(ErrorKind::Cancelled, "interrupted; no output was left half-written"); }

Error internal_error(const std::string& reason)
{
    return Error(ErrorKind::Internal, "internal error: " + reason);
}

}  // namespace modestack
