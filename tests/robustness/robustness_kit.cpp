#include "tests/robustness/robustness_kit.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

namespace modestack::robustness {
namespace stdfs = std::filesystem;

namespace {

std::uint32_t read_u32(const std::string& bytes, std::size_t at)
{
    if (at + 4 > bytes.size())
        throw std::runtime_error("EXR layout: read past the end");
    std::uint32_t value = 0;
    std::memcpy(&value, bytes.data() + at, 4);  // EXR is little-endian, like every test machine
    return value;
}

std::uint64_t read_u64(const std::string& bytes, std::size_t at)
{
    if (at + 8 > bytes.size())
        throw std::runtime_error("EXR layout: read past the end");
    std::uint64_t value = 0;
    std::memcpy(&value, bytes.data() + at, 8);
    return value;
}

std::size_t end_of_string(const std::string& bytes, std::size_t at)
{
    std::size_t zero = bytes.find('\0', at);
    if (zero == std::string::npos)
        throw std::runtime_error("EXR layout: unterminated name");
    return zero + 1;
}

// Bytes before the compressed data of a chunk: y and size for scanlines; tile
// x, y, level x, level y and size for tiles.
std::size_t chunk_prefix_bytes(const std::string& bytes)
{
    constexpr std::uint32_t kTiledFlag = 0x200;
    return (read_u32(bytes, 4) & kTiledFlag) ? 20 : 8;
}

}  // namespace

ExrLayoutOffsets parse_exr_layout(const std::string& path)
{
    std::string bytes = read_bytes(path);
    constexpr std::uint32_t kMagic = 20000630, kMultipartFlag = 0x1000, kDeepFlag = 0x800;
    if (read_u32(bytes, 0) != kMagic)
        throw std::runtime_error(path + " is not an EXR");
    if (read_u32(bytes, 4) & (kMultipartFlag | kDeepFlag))
        throw std::runtime_error(path + ": only single-part flat EXRs are parsed");
    // Attributes: name\0 type\0 int32 size, value; a zero byte ends the header.
    std::size_t at = 8;
    while (at < bytes.size() && bytes[at] != '\0') {
        std::size_t type = end_of_string(bytes, at);
        std::size_t size_at = end_of_string(bytes, type);
        at = size_at + 4 + read_u32(bytes, size_at);
    }
    if (at >= bytes.size())
        throw std::runtime_error(path + ": header runs past the end");
    ExrLayoutOffsets layout;
    layout.header_end = at + 1;
    layout.file_size = bytes.size();
    // The table ends where the first chunk starts; writers put chunk 0 first.
    std::uint64_t first = read_u64(bytes, layout.header_end);
    if (first <= layout.header_end || (first - layout.header_end) % 8 != 0 || first >= bytes.size())
        throw std::runtime_error(path + ": unexpected offset table");
    for (std::size_t entry = layout.header_end; entry < first; entry += 8)
        layout.chunk_offsets.push_back(read_u64(bytes, entry));
    return layout;
}

const char* damage_name(Damage damage)
{
    switch (damage) {
    case Damage::ZeroBytes: return "zero-byte file";
    case Damage::BadMagic: return "not an EXR (magic number overwritten)";
    case Damage::HeaderCut: return "truncated in the header";
    case Damage::OffsetTableCut: return "truncated in the offset table";
    case Damage::OffsetTableGarbage: return "offset table overwritten";
    case Damage::ChunkGarbage: return "compressed chunk corrupted";
    case Damage::ChunkCut: return "truncated inside a compressed chunk";
    case Damage::HugeAttribute: return "an attribute claiming 1.7 GB";
    }
    return "?";
}

void damage_exr(const std::string& path, Damage damage)
{
    std::string bytes = read_bytes(path);
    ExrLayoutOffsets layout = parse_exr_layout(path);
    std::size_t chunk = layout.chunk_offsets.front();
    std::size_t data = chunk + chunk_prefix_bytes(bytes);
    std::size_t data_size = read_u32(bytes, data - 4);
    switch (damage) {
    case Damage::ZeroBytes: bytes.clear(); break;
    case Damage::BadMagic: bytes.replace(0, 4, "junk"); break;
    case Damage::HeaderCut: bytes.resize(layout.header_end / 2); break;
    case Damage::OffsetTableCut: bytes.resize(layout.header_end + 4); break;
    case Damage::OffsetTableGarbage:
        std::fill(bytes.begin() + layout.header_end, bytes.begin() + chunk, '\xff');
        break;
    case Damage::ChunkGarbage:
        if (data_size < 24)
            throw std::runtime_error(path + ": first chunk too small to corrupt");
        for (std::size_t i = data + data_size / 3; i < data + data_size / 3 + 8; ++i)
            bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
        break;
    case Damage::ChunkCut: bytes.resize(data + 4); break;
    case Damage::HugeAttribute: {
        std::size_t size_at = end_of_string(bytes, end_of_string(bytes, 8));
        const std::uint32_t huge = 0x68000013;
        std::memcpy(bytes.data() + size_at, &huge, 4);
        break;
    }
    }
    write_bytes(path, bytes);
}

std::string read_bytes(const std::string& path)
{
    std::ifstream file(path, std::ios::binary);
    if (!file)
        throw std::runtime_error("cannot read " + path);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
}

void write_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!file)
        throw std::runtime_error("cannot write " + path);
}

bool one_line(const std::string& text) { return text.size() > 1 && text.find('\n') == text.size() - 1; }

namespace {
std::vector<std::string> files_under(const std::string& directory, bool temporary)
{
    std::vector<std::string> names;
    std::error_code error;
    if (!stdfs::is_directory(directory, error))
        return names;
    for (const auto& entry : stdfs::recursive_directory_iterator(directory, error)) {
        if (!entry.is_regular_file())
            continue;
        std::string name = entry.path().filename().string();
        bool is_temporary = name.size() > 14 && name.compare(name.size() - 14, 14, ".modestack-tmp") == 0;
        if (is_temporary == temporary)
            names.push_back(stdfs::relative(entry.path(), directory).string());
    }
    std::sort(names.begin(), names.end());
    return names;
}
}  // namespace

std::vector<std::string> temporary_files(const std::string& directory) { return files_under(directory, true); }
std::vector<std::string> final_files(const std::string& directory) { return files_under(directory, false); }

BackgroundRun::BackgroundRun(const std::string& arguments, const std::string& stderr_path,
                             const std::string& environment)
{
    // `env` execs the binary in turn: the pid stays the binary's.
    std::string command = fmt::format("exec env {} {} {} >/dev/null 2>{} </dev/null", environment, MODESTACK_BINARY,
                                      arguments, stderr_path);
    m_pid = fork();
    if (m_pid < 0)
        throw std::runtime_error("fork failed");
    if (m_pid == 0) {
        execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
        _exit(127);
    }
}

BackgroundRun::~BackgroundRun()
{
    if (!m_reaped) {
        ::kill(m_pid, SIGKILL);
        wait();
    }
}

void BackgroundRun::signal(int signal_number)
{
    if (!m_reaped)
        ::kill(m_pid, signal_number);
}

int BackgroundRun::wait()
{
    if (!m_reaped) {
        while (waitpid(m_pid, &m_status, 0) < 0 && errno == EINTR) {
        }
        m_reaped = true;
    }
    return WIFEXITED(m_status) ? WEXITSTATUS(m_status) : 128 + WTERMSIG(m_status);
}

bool BackgroundRun::running()
{
    if (m_reaped)
        return false;
    int status = 0;
    pid_t done = waitpid(m_pid, &status, WNOHANG);
    if (done == m_pid) {
        m_status = status;
        m_reaped = true;
        return false;
    }
    return true;
}

PausePoint::PausePoint(const std::string& call, const std::string& directory) : m_call(call), m_directory(directory)
{
    stdfs::create_directories(directory);
}

std::string PausePoint::environment() const
{
    // A sanitized binary wants its runtime first among the loaded libraries; the
    // plain hook before it is harmless.
    const char* asan_options = std::getenv("ASAN_OPTIONS");
    std::string asan = asan_options && *asan_options ? std::string(asan_options) + ":" : std::string();
    return fmt::format("LD_PRELOAD='{}' PAUSE_HOOK_AT='{}' PAUSE_HOOK_DIR='{}' ASAN_OPTIONS='{}verify_asan_link_order=0'",
                       MODESTACK_PAUSE_HOOK, m_call, m_directory, asan);
}

bool PausePoint::wait_until_held(BackgroundRun& run) const
{
    const std::string held = m_directory + "/paused";
    while (run.running()) {
        if (stdfs::exists(held))
            return true;
        usleep(2000);
    }
    return stdfs::exists(held);
}

void PausePoint::release() const { std::ofstream(m_directory + "/resume").put('\n'); }

TinyFilesystem::TinyFilesystem(const std::string& parent, const std::string& size, bool read_only)
    : m_path(parent + "/tiny")
{
    stdfs::create_directories(m_path);
    if (geteuid() != 0) {
        m_why_not = "not running as root, cannot mount a tmpfs";
        return;
    }
    std::string options = "size=" + size;
    unsigned long flags = MS_NOSUID | MS_NODEV | (read_only ? MS_RDONLY : 0);
    if (mount("tmpfs", m_path.c_str(), "tmpfs", flags, options.c_str()) != 0) {
        m_why_not = fmt::format("mount -t tmpfs failed: {}", std::strerror(errno));
        return;
    }
    m_mounted = true;
}

TinyFilesystem::~TinyFilesystem()
{
    if (m_mounted)
        umount2(m_path.c_str(), MNT_DETACH);
    std::error_code ignored;
    stdfs::remove(m_path, ignored);
}

void write_rgb_exr(const std::string& path, int width, int height, int x, int y, int parts)
{
    std::vector<OIIO::ImageSpec> specs;
    for (int part = 0; part < parts; ++part) {
        OIIO::ImageSpec spec(width, height, 3, OIIO::TypeHalf);
        spec.x = x;
        spec.y = y;
        spec.attribute("compression", "zip");
        spec.attribute("name", fmt::format("part{}", part));
        specs.push_back(spec);
    }
    std::vector<float> pixels(static_cast<std::size_t>(width) * height * 3);
    for (std::size_t i = 0; i < pixels.size(); ++i)
        pixels[i] = 0.25f + 0.001f * static_cast<float>(i % 97);
    auto output = OIIO::ImageOutput::create(path);
    bool ok = output && output->open(path, parts, specs.data());
    for (int part = 0; ok && part < parts; ++part) {
        if (part > 0)
            ok = output->open(path, specs[part], OIIO::ImageOutput::AppendSubimage);
        ok = ok && output->write_image(OIIO::TypeFloat, pixels.data());
    }
    if (!ok || !output->close())
        throw std::runtime_error("cannot write test image " + path);
}

std::string frame_file(const std::string& printf_pattern, int frame)
{
    std::vector<char> name(printf_pattern.size() + 32);
    std::snprintf(name.data(), name.size(), printf_pattern.c_str(), frame);
    return name.data();
}

}  // namespace modestack::robustness
