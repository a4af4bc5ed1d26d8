#include "io/sequence.h"

#include "core/common/error.h"

#include <OpenImageIO/filesystem.h>
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <set>

namespace modestack::io {
namespace {

namespace fs = OIIO::Filesystem;

// OIIO reads each '#' as four digits; a run of N > 1 '#' means N digits to
// every other tool, so rewrite such runs as '@' (one digit each) first.
std::string runs_of_hash_to_at(const std::string& pattern)
{
    std::string out;
    for (size_t i = 0; i < pattern.size();) {
        size_t run = 0;
        while (i + run < pattern.size() && pattern[i + run] == '#')
            ++run;
        if (run > 1) {
            out.append(run, '@');
            i += run;
        } else {
            out.push_back(pattern[i++]);
        }
    }
    return out;
}

bool has_frame_token(const std::string& pattern)
{
    if (pattern.find_first_of("#@") != std::string::npos)
        return true;
    size_t percent = pattern.find('%');
    return percent != std::string::npos && pattern.find('d', percent) != std::string::npos;
}

// True when `printf_pattern` has exactly one frame conversion (%d or %0Nd, at
// most two width digits) and every other '%' is a literal "%%". OIIO formats
// file names with this pattern, and its formatter aborts the process on
// anything else ("%s", "%n", a second "%d"); the fuzzer found that. A '#' or
// '@' left over is a second frame token that OIIO would keep literally
// ("o%d/name.####.exr" wrote o1/name.@@@@.exr): one frame token only.
bool is_safe_printf_pattern(const std::string& pattern)
{
    if (pattern.find_first_of("#@") != std::string::npos)
        return false;
    int conversions = 0;
    for (size_t i = 0; i < pattern.size(); ++i) {
        if (pattern[i] != '%')
            continue;
        if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
            ++i;
            continue;
        }
        size_t j = i + 1;
        while (j < pattern.size() && pattern[j] >= '0' && pattern[j] <= '9')
            ++j;
        if (j >= pattern.size() || pattern[j] != 'd' || j - i - 1 > 2)
            return false;
        ++conversions;
        i = j;
    }
    return conversions == 1;
}

std::string format_frame(const std::string& printf_pattern, int frame)
{
    std::vector<std::string> files;
    if (!fs::enumerate_file_sequence(printf_pattern, {frame}, files) || files.size() != 1)
        throw usage_error(fmt::format("cannot make a file name from pattern '{}'", printf_pattern));
    return files.front();
}

// A shot of a million frames is 11 hours at 24 fps; a longer range is a typo
// ("1-10000000000") and would need gigabytes for its frame list.
constexpr long long kMaxFrames = 1000000;

// Parses an optionally signed integer of at most 10 digits at `at` that fits an
// int; false when there is none.
bool parse_integer(const std::string& text, size_t& at, long long& value)
{
    size_t position = at;
    bool negative = position < text.size() && text[position] == '-';
    if (negative || (position < text.size() && text[position] == '+'))
        ++position;
    size_t digits = position;
    value = 0;
    while (position < text.size() && text[position] >= '0' && text[position] <= '9' && position - digits < 10)
        value = value * 10 + (text[position++] - '0');
    if (position == digits || (position < text.size() && text[position] >= '0' && text[position] <= '9'))
        return false;
    if (negative)
        value = -value;
    if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max())
        return false;
    at = position;
    return true;
}

// One comma-separated part of a range: "7", "1-10", "1-10x2" (every 2nd) or
// "1-10y2" (all but every 2nd), ascending or descending, as OIIO reads them.
// Our own strict parser, not OIIO's enumerate_sequence: that one accepts
// garbage ("1-111a--1") and expands any span, however long, before we can
// check it. Returns false when the part is malformed.
bool parse_range_part(const std::string& part, long long frames_so_far, const std::string& option,
                      const std::string& spec, std::vector<int>& frames)
{
    size_t at = 0;
    long long first = 0, last = 0, step = 1;
    char mode = 'x';
    if (!parse_integer(part, at, first))
        return false;
    last = first;
    if (at < part.size() && part[at] == '-') {
        ++at;
        if (!parse_integer(part, at, last))
            return false;
        if (at < part.size() && (part[at] == 'x' || part[at] == 'y')) {
            mode = part[at++];
            if (!parse_integer(part, at, step) || step < 1)
                return false;
        }
    }
    if (at != part.size())
        return false;
    long long span = (last >= first ? last - first : first - last) + 1;
    long long count = mode == 'x' ? (span - 1) / step + 1 : span - ((span - 1) / step + 1);
    if (frames_so_far + count > kMaxFrames)
        throw usage_error(fmt::format("{} '{}': more than {} frames (a typo?)", option, spec, kMaxFrames));
    long long direction = last >= first ? 1 : -1;
    if (mode == 'x') {
        for (long long i = 0; i < count; ++i)
            frames.push_back(static_cast<int>(first + direction * i * step));
    } else if (step > 1) {
        // At most count * step / (step - 1) <= 2 * kMaxFrames iterations.
        for (long long i = 0; i < span; ++i)
            if (i % step != 0)
                frames.push_back(static_cast<int>(first + direction * i));
    }
    return true;
}

// The file name of `printf_pattern` split at its frame conversion, with "%%"
// read as "%": "shot.%04d.exr" is "shot." and ".exr".
struct FrameSlot {
    std::string before, after;
};

FrameSlot frame_slot(const std::string& file_name)
{
    FrameSlot slot;
    std::string* side = &slot.before;
    for (size_t i = 0; i < file_name.size(); ++i) {
        if (file_name[i] != '%') {
            side->push_back(file_name[i]);
        } else if (i + 1 < file_name.size() && file_name[i + 1] == '%') {
            side->push_back('%');
            ++i;
        } else {
            i = file_name.find('d', i);
            if (i == std::string::npos)
                break;
            side = &slot.after;
        }
    }
    return slot;
}

// The frames of `printf_pattern` (one frame conversion, in its file name) on
// disk, ascending. The one rule for every command that reads a sequence: a
// file is a frame when the pattern writes exactly its name for the number in
// it, so "%04d" (and "####") finds name.0007.exr and name.12345.exr, and "%d"
// (and "@") finds name.7.exr but not name.007.exr. We list the directory
// ourselves: OIIO's scan finds nothing for "%d", and builds a regex of the
// directory's name, so "(" or "+" in a path broke it.
std::vector<std::pair<int, std::string>> frames_on_disk(const std::string& printf_pattern)
{
    std::string directory = fs::parent_path(printf_pattern);
    FrameSlot slot = frame_slot(fs::filename(printf_pattern));
    std::vector<std::pair<int, std::string>> found;
    std::error_code error;
    for (std::filesystem::directory_iterator entry(directory.empty() ? "." : directory, error), end;
         !error && entry != end; entry.increment(error)) {
        std::string name = entry->path().filename().string();
        if (name.size() <= slot.before.size() + slot.after.size() ||
            name.compare(0, slot.before.size(), slot.before) ||
            name.compare(name.size() - slot.after.size(), slot.after.size(), slot.after))
            continue;
        std::string number =
            name.substr(slot.before.size(), name.size() - slot.before.size() - slot.after.size());
        size_t at = 0;
        long long frame = 0;
        if (!parse_integer(number, at, frame) || at != number.size())
            continue;
        std::string file = format_frame(printf_pattern, static_cast<int>(frame));
        std::error_code type_error;
        if (fs::filename(file) == name && entry->is_regular_file(type_error))
            found.emplace_back(static_cast<int>(frame), file);
    }
    std::sort(found.begin(), found.end());
    return found;
}

}  // namespace

// OIIO parses patterns with std::regex, which recurses once per character: a
// 120 kB pattern overflowed the stack (found by fuzz/frame_range). No path is
// longer than PATH_MAX, so nothing longer is a pattern.
constexpr size_t kMaxPatternBytes = 4096;

// Throws a usage error for a pattern longer than any path, quoting its start only.
static void require_path_length(const std::string& pattern, const char* what)
{
    if (pattern.size() > kMaxPatternBytes)
        throw usage_error(fmt::format("{} '{}...' is {} bytes long; a path has at most {}", what,
                                      pattern.substr(0, 40), pattern.size(), kMaxPatternBytes));
}

// Normalizes an input pattern, or throws a usage error saying how to write one.
static void require_frame_token(const std::string& pattern, std::string& printf_pattern, std::string& embedded)
{
    require_path_length(pattern, "pattern");
    if (!normalize_pattern(pattern, printf_pattern, embedded))
        throw usage_error(fmt::format("'{}' is not a frame-sequence pattern (write name.####.exr, name.%04d.exr "
                                      "or name.@.exr; a literal % as %%)",
                                      pattern));
}

std::vector<int> parse_frame_range(const std::string& spec, const std::string& option)
{
    std::vector<int> frames;
    bool ok = !spec.empty();
    for (size_t at = 0; ok && at <= spec.size();) {
        size_t comma = spec.find(',', at);
        std::string part = spec.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
        ok = parse_range_part(part, static_cast<long long>(frames.size()), option, spec, frames);
        at = comma == std::string::npos ? spec.size() + 1 : comma + 1;
    }
    if (!ok || frames.empty())
        throw usage_error(fmt::format("{} '{}': not a frame range (examples: 1-48, 1001-1100, 1-100x2, 1,3,7-9)",
                                      option, spec));
    std::set<int> seen;
    for (int frame : frames)
        if (!seen.insert(frame).second)
            throw usage_error(fmt::format("{} '{}': frame {} is listed twice", option, spec, frame));
    return frames;
}

bool normalize_pattern(const std::string& pattern, std::string& printf_pattern, std::string& embedded_range)
{
    printf_pattern.clear();
    embedded_range.clear();
    if (pattern.size() > kMaxPatternBytes || !has_frame_token(pattern))
        return false;
    if (!fs::parse_pattern(runs_of_hash_to_at(pattern).c_str(), 0, printf_pattern, embedded_range) ||
        !is_safe_printf_pattern(printf_pattern)) {
        printf_pattern.clear();
        embedded_range.clear();
        return false;
    }
    return true;
}

FrameSequence find_input_sequence(const std::string& pattern, const std::string& frame_range)
{
    FrameSequence sequence;
    sequence.pattern = pattern;
    std::string embedded;
    require_frame_token(pattern, sequence.printf_pattern, embedded);
    std::string range = frame_range.empty() ? embedded : frame_range;

    if (!range.empty()) {
        sequence.frames = parse_frame_range(range);
        for (int frame : sequence.frames) {
            std::string file = format_frame(sequence.printf_pattern, frame);
            if (!fs::exists(file))
                throw Error(ErrorKind::BadInput, fmt::format("frame {} is missing", frame), file, frame);
            if (fs::is_directory(file))
                throw Error(ErrorKind::BadInput, "is a directory, not an image file", file, frame);
            sequence.files.push_back(file);
        }
        return sequence;
    }

    FrameSequence found = scan_input_sequence(pattern);
    std::vector<int> gaps = missing_frames(found.frames);
    if (!gaps.empty())
        throw bad_input(pattern, fmt::format("missing frames between {} and {}: {} (use --frames to choose the "
                                             "frames wanted)",
                                             found.frames.front(), found.frames.back(), describe_frames(gaps)));
    return found;
}

FrameSequence scan_input_sequence(const std::string& pattern)
{
    FrameSequence sequence;
    sequence.pattern = pattern;
    std::string embedded;
    require_frame_token(pattern, sequence.printf_pattern, embedded);
    std::string directory = fs::parent_path(sequence.printf_pattern);
    if (!directory.empty() && !fs::is_directory(directory))
        throw bad_input(directory, "directory does not exist");
    std::vector<std::pair<int, std::string>> found = frames_on_disk(sequence.printf_pattern);
    if (found.empty())
        throw bad_input(pattern, "no frames found on disk");
    for (auto& [frame, file] : found) {
        sequence.frames.push_back(frame);
        sequence.files.push_back(file);
    }
    return sequence;
}

std::vector<int> missing_frames(const std::vector<int>& frames)
{
    std::vector<int> gaps;
    for (size_t i = 1; i < frames.size(); ++i)
        for (int missing = frames[i - 1] + 1; missing < frames[i]; ++missing)
            gaps.push_back(missing);
    return gaps;
}

FrameSequence output_sequence(const std::string& pattern, const std::vector<int>& frames)
{
    FrameSequence sequence;
    sequence.pattern = pattern;
    sequence.frames = frames;
    std::string embedded;
    require_path_length(pattern, "output");
    if (!normalize_pattern(pattern, sequence.printf_pattern, embedded)) {
        if (has_frame_token(pattern))
            throw usage_error(fmt::format("output '{}' is not a frame-sequence pattern (one frame token: ####, @@@@ or "
                                          "%04d; write a literal % as %%)",
                                          pattern));
        if (frames.size() > 1)
            throw usage_error(fmt::format("output '{}' has no frame token (write name.####.exr)", pattern));
        sequence.printf_pattern = pattern;
        sequence.files.assign(frames.size(), pattern);
        return sequence;
    }
    if (!embedded.empty())
        throw usage_error(fmt::format("output pattern '{}' must not contain a frame range", pattern));
    for (int frame : frames)
        sequence.files.push_back(format_frame(sequence.printf_pattern, frame));
    return sequence;
}

std::string describe_frames(const std::vector<int>& frames)
{
    std::string text;
    size_t i = 0;
    while (i < frames.size()) {
        // Longest run with a constant positive step starting at i.
        size_t j = i + 1;
        int step = j < frames.size() ? frames[j] - frames[i] : 1;
        if (step <= 0)
            step = 1;
        while (j < frames.size() && frames[j] - frames[j - 1] == step)
            ++j;
        if (!text.empty())
            text += ",";
        size_t count = j - i;
        if (count >= 3 || (count == 2 && step == 1)) {
            text += fmt::format("{}-{}", frames[i], frames[j - 1]);
            if (step != 1)
                text += fmt::format("x{}", step);
            i = j;
        } else {
            text += std::to_string(frames[i]);
            ++i;
        }
    }
    return text;
}

}  // namespace modestack::io
