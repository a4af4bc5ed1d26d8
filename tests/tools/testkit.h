// Helpers shared by the io and end-to-end tests: a temporary directory, small
// EXR files and sequences made on the fly (any channels, pixel types, tiling),
// reading channels back, and running the real `modestack` binary.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace modestack::testkit {

/// A fresh directory under /tmp, removed with everything in it on destruction.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::string& path() const { return m_path; }
    std::string file(const std::string& name) const { return m_path + "/" + name; }

private:
    std::string m_path;
};

/// Value of channel `channel` at pixel (x, y); `frame` for sequences.
using PixelFunction = std::function<float(int frame, int x, int y, int channel)>;

/// How to write a test image.
struct ExrLayout {
    int width = 16;
    int height = 12;
    std::vector<std::string> channel_names{"R", "G", "B"};
    std::vector<std::string> channel_types;  ///< empty = all "half"
    int tile_size = 0;                       ///< 0 = scanline
    std::string compression = "zip";
    std::vector<std::pair<std::string, std::string>> attributes;  ///< string attributes
};

/// Writes one EXR (directly with OIIO, not through modestack's io layer).
void write_exr(const std::string& path, const ExrLayout& layout, int frame, const PixelFunction& value);
/// Writes frames of a printf-style pattern ("dir/shot.%04d.exr").
std::vector<std::string> write_sequence(const std::string& printf_pattern, const std::vector<int>& frames,
                                        const ExrLayout& layout, const PixelFunction& value);
/// Reads the named channels of an EXR as float, interleaved.
std::vector<float> read_channels(const std::string& path, const std::vector<std::string>& channels);
/// Reads all channels in native pixel types (bytes), for bit-exact checks.
std::vector<unsigned char> read_native(const std::string& path);
/// A string attribute of an EXR header ("" when absent).
std::string read_string_attribute(const std::string& path, const std::string& name);
/// Channel names of an EXR, in OIIO order.
std::vector<std::string> read_channel_names(const std::string& path);

/// Outcome of running the binary.
struct CliResult {
    int exit_code = -1;
    std::string out;
    std::string err;
};
/// Runs `modestack <arguments>` (arguments are passed to /bin/sh as written).
CliResult run_modestack(const std::string& arguments);
/// Runs `<launcher> modestack <arguments>`, e.g. under "mpirun -n 2".
CliResult run_modestack_under(const std::string& launcher, const std::string& arguments);

/// The line that reports a test as skipped: what ctest's SKIP_REGULAR_EXPRESSION
/// looks for (tests/CMakeLists.txt).
inline constexpr const char* kSkippedMarker = "SKIPPED:";
/// Reports that the running test cannot check what it claims here, and why:
/// prints "SKIPPED: <reason>" on stdout, which ctest shows as skipped rather than
/// passed. The caller returns right after (a test binary run by hand goes on
/// with its other test cases).
void report_skipped(const std::string& reason);

/// A file's whole contents ("" when it cannot be opened).
std::string read_text(const std::string& path);

/// Files in a directory (names only, sorted), hidden ones included.
std::vector<std::string> list_directory(const std::string& path);

}  // namespace modestack::testkit
