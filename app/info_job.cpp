// check_sequence(): a header that cannot be read or a check that fails marks
// that frame bad, and the next frame is read all the same.
#include "app/info_job.h"

#include "core/common/error.h"

namespace modestack::app {
namespace {

// The reason of a bad-input Error about `file`, without the "file: " its
// message starts with.
std::string reason_of(const Error& error, const std::string& file)
{
    std::string message = error.what();
    const std::string prefix = file + ": ";
    return message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
}

} // namespace

const CheckedFrame* InfoFindings::reference() const
{
    for (const CheckedFrame& frame : frames)
        if (frame.header)
            return &frame;
    return nullptr;
}

std::vector<int> InfoFindings::bad_frames() const
{
    std::vector<int> bad;
    for (const CheckedFrame& frame : frames)
        if (!frame.problem.empty())
            bad.push_back(frame.frame);
    return bad;
}

InfoFindings check_sequence(const io::FrameSequence& sequence, FrameCheckDepth depth)
{
    InfoFindings findings;
    findings.sequence = sequence;
    findings.depth = depth;
    for (std::size_t i = 0; i < sequence.files.size(); ++i) {
        CheckedFrame checked;
        checked.frame = sequence.frames[i];
        checked.file = sequence.files[i];
        // The table check first: it names a file cut short as such, where the
        // header reader may only say "unexpected end of file".
        checked.problem = io::check_chunk_tables(checked.file);
        try {
            checked.header = io::read_frame_header(checked.file);
        } catch (const Error& error) {
            if (error.kind() != ErrorKind::BadInput)
                throw;
            if (checked.problem.empty())
                checked.problem = reason_of(error, checked.file);
        }
        if (checked.header && checked.problem.empty() && depth == FrameCheckDepth::EveryChunk)
            checked.problem = io::check_every_chunk(checked.file);
        findings.frames.push_back(std::move(checked));
    }
    return findings;
}

} // namespace modestack::app
