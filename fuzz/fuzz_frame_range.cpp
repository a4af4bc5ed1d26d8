// Fuzz harness: frame-sequence patterns and frame ranges (io/sequence.h). The
// input is a pattern, a newline, and a range. Invariants checked beyond "no
// crash": a range of sorted distinct frames survives describe_frames() and
// parse_frame_range() unchanged, and every error is a modestack::Error.
#include "core/common/error.h"
#include "io/sequence.h"

#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

// Describing a long gap list costs time linear in the gap; keep inputs cheap.
constexpr long long kMaxSpan = 100000;

void check(bool condition)
{
    if (!condition)
        std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    std::string input(reinterpret_cast<const char*>(data), size);
    std::size_t newline = input.find('\n');
    std::string pattern = input.substr(0, newline);
    std::string range = newline == std::string::npos ? std::string() : input.substr(newline + 1);
    using modestack::Error;

    std::string printf_pattern, embedded;
    if (modestack::io::normalize_pattern(pattern, printf_pattern, embedded)) {
        check(!printf_pattern.empty());
        try {
            modestack::io::FrameSequence output = modestack::io::output_sequence(pattern, {1, 2, 1001});
            check(output.files.size() == 3);
        } catch (const Error&) {
        }
    }
    try {
        std::vector<int> frames = modestack::io::parse_frame_range(range);
        check(!frames.empty());
        bool ascending = true;
        for (std::size_t i = 1; i < frames.size(); ++i)
            ascending = ascending && frames[i] > frames[i - 1];
        long long span = static_cast<long long>(frames.back()) - frames.front();
        if (ascending && span < kMaxSpan) {
            std::string described = modestack::io::describe_frames(frames);
            check(modestack::io::parse_frame_range(described) == frames);
            std::vector<int> gaps = modestack::io::missing_frames(frames);
            check(static_cast<long long>(gaps.size() + frames.size()) == span + 1);
        }
    } catch (const Error&) {
    }
    return 0;
}
