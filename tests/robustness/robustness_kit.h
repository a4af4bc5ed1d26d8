// Helpers for the robustness tests: damaging a valid EXR at a chosen place of
// its layout (header, offset table, a compressed chunk), listing what a run
// left in an output directory (final names and temporary files), running the
// binary in the background to signal it (held at a chosen call until it is
// signalled), and mounting a tiny tmpfs when the tests run as root.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::robustness {

/// Where the parts of a single-part scanline or tiled EXR lie, in bytes.
struct ExrLayoutOffsets {
    std::size_t header_end = 0;             ///< first byte after the header's terminating zero
    std::vector<std::uint64_t> chunk_offsets;  ///< the offset table (one entry per chunk)
    std::size_t file_size = 0;
};

/// Parses the header of a single-part EXR just far enough to find the offset
/// table and the chunks. Throws std::runtime_error on anything else.
ExrLayoutOffsets parse_exr_layout(const std::string& path);

/// The ways a test damages a valid EXR.
enum class Damage {
    ZeroBytes,          ///< an empty file
    BadMagic,           ///< the first four bytes overwritten
    HeaderCut,          ///< cut in the middle of the header
    OffsetTableCut,     ///< cut after half of the first offset
    OffsetTableGarbage, ///< every offset overwritten with 0xff bytes
    ChunkGarbage,       ///< eight bytes inside the first chunk's compressed data flipped
    ChunkCut,           ///< cut four bytes into the first chunk's compressed data
    HugeAttribute,      ///< the first attribute's size field set to 1.7 GB
};
/// Short name for messages and the docs table.
const char* damage_name(Damage damage);
/// Damages the valid EXR at `path` in place.
void damage_exr(const std::string& path, Damage damage);

/// The whole file as bytes.
std::string read_bytes(const std::string& path);
/// Writes `bytes` over the whole file.
void write_bytes(const std::string& path, const std::string& bytes);

/// True when `text` is exactly one non-empty line ending in '\n'.
bool one_line(const std::string& text);

/// Files under `directory` (recursively, relative paths, sorted) whose name is
/// a modestack temporary file (`.NAME.HOST.PID-N.modestack-tmp`).
std::vector<std::string> temporary_files(const std::string& directory);
/// Every other regular file under `directory` (recursively, relative, sorted).
std::vector<std::string> final_files(const std::string& directory);

/// `modestack` started in the background, stderr captured to a file.
class BackgroundRun {
public:
    /// Starts `modestack <arguments>` (split by /bin/sh, which then execs the
    /// binary) with `environment` ("NAME=value ...", e.g. PausePoint's) added.
    BackgroundRun(const std::string& arguments, const std::string& stderr_path, const std::string& environment = "");
    ~BackgroundRun();
    BackgroundRun(const BackgroundRun&) = delete;
    BackgroundRun& operator=(const BackgroundRun&) = delete;

    /// Sends `signal_number` to the process.
    void signal(int signal_number);
    /// Waits for the process; returns its exit code, or 128 + the signal that killed it.
    int wait();
    /// True while the process has not exited (does not reap it).
    bool running();

private:
    int m_pid = -1;
    bool m_reaped = false;
    int m_status = 0;
};

/// A point where a BackgroundRun started with environment() stops until
/// release(): the test's pause hook (pause_hook.cpp), preloaded into the binary.
/// The signal a test sends while the run is held always lands, and lands while
/// the run is where the test wants it.
class PausePoint {
public:
    /// `call` is "rename:N" (after the Nth rename: N outputs committed) or
    /// "libdeflate_zlib_compress:N" (before the Nth ZIP chunk written); the hook's
    /// files go in `directory`, which is created.
    PausePoint(const std::string& call, const std::string& directory);
    std::string environment() const;
    /// Waits until `run` is held at the point; false when it ended first.
    bool wait_until_held(BackgroundRun& run) const;
    /// Lets the run go on once no signal is pending for it (its handler ran).
    void release() const;

private:
    std::string m_call;
    std::string m_directory;
};

/// A tmpfs of `size` (mount option, e.g. "160k") mounted on a fresh directory
/// inside `parent`; unmounted on destruction. Needs root: mounted() says
/// whether it worked, why_not() why not.
class TinyFilesystem {
public:
    TinyFilesystem(const std::string& parent, const std::string& size, bool read_only = false);
    ~TinyFilesystem();
    TinyFilesystem(const TinyFilesystem&) = delete;
    TinyFilesystem& operator=(const TinyFilesystem&) = delete;

    bool mounted() const { return m_mounted; }
    const std::string& why_not() const { return m_why_not; }
    const std::string& path() const { return m_path; }

private:
    std::string m_path;
    bool m_mounted = false;
    std::string m_why_not;
};

/// Writes a smooth half RGB EXR of `width`×`height` whose data window starts
/// at (`x`, `y`), with `parts` parts (1 = an ordinary single-part file).
void write_rgb_exr(const std::string& path, int width, int height, int x = 0, int y = 0, int parts = 1);

/// The name of frame `frame` of a printf pattern ("dir/d.%04d.exr").
std::string frame_file(const std::string& printf_pattern, int frame);

}  // namespace modestack::robustness
