// The one exception type of modestack. It is thrown where a problem is found and
// caught once in main(), which prints `modestack: <what()>` and exits with
// exit_code(kind). It carries the file, frame and channel the problem is about so
// that the message names them; what() is always a single line.
#pragma once

#include <stdexcept>
#include <string>

namespace modestack {

/// What kind of failure, and so which exit code (documented in modestack(1)).
enum class ErrorKind {
    BadInput = 1,  ///< bad or missing input file, unwritable output, failed run
    Usage = 2,     ///< bad command line: unknown option, value out of range
    Internal = 3,  ///< a bug: an invariant that should never break
    Cancelled = 4, ///< stopped by SIGINT/SIGTERM; main exits with 128 + signal
};

/// Marks "no frame number" in Error::frame().
inline constexpr int kNoFrame = -2147483647 - 1;

/// An error a user can act on: a one-line reason, plus where it happened.
class Error : public std::runtime_error {
public:
    /// `reason` says what is wrong and, where it helps, what to do; `file`
    /// (which what() prefixes) and `frame` are optional context.
    Error(ErrorKind kind, const std::string& reason, const std::string& file = {}, int frame = kNoFrame);

    ErrorKind kind() const { return m_kind; }
    const std::string& file() const { return m_file; }
    int frame() const { return m_frame; }

private:
    ErrorKind m_kind;
    std::string m_file;
    int m_frame;
};

/// Error about an input or output file (exit code 1).
Error bad_input(const std::string& file, const std::string& reason);
/// Error about the command line (exit code 2).
Error usage_error(const std::string& reason);
/// Error for a broken internal invariant (exit code 3).
Error internal_error(const std::string& reason);

/// Error for work stopped by a cancel request (see core/common/progress.h).
Error cancelled_error();

/// The process exit code for an error kind (Cancelled: 130, main refines it by signal).
inline int exit_code(ErrorKind kind) { return kind == ErrorKind::Cancelled ? 130 : static_cast<int>(kind); }

}  // namespace modestack
