// Streaming comparison of a test sequence against its reference (see sequence_comparison.h).
#include "core/metrics/sequence_comparison.h"

#include <cassert>

namespace modestack::metrics {

SequenceComparison::SequenceComparison(std::int64_t pixel_count, int channels,
                                       const PixelThresholds& thresholds, const VerdictRule& rule)
    : m_pixel_count(pixel_count), m_channels(channels), m_thresholds(thresholds), m_rule(rule)
{
    assert(pixel_count >= 0 && channels >= 0);
}

FrameComparison SequenceComparison::add_frame(const float* test, const float* reference)
{
    std::int64_t value_count = m_pixel_count * m_channels;
    FrameComparison frame;
    frame.sums = frame_errors(test, reference, m_pixel_count, m_channels, m_thresholds);
    if (m_frames > 0)
        add_flicker(test, reference, m_previous_test.data(), m_previous_reference.data(), value_count,
                    frame.sums);
    frame.verdict = judge(frame.sums, m_rule);

    m_previous_test.assign(test, test + value_count);
    m_previous_reference.assign(reference, reference + value_count);
    m_shot.merge(frame.sums);
    m_verdict = worst(m_verdict, frame.verdict);
    ++m_frames;
    m_frames_failing += frame.verdict == Verdict::Failure ? 1 : 0;
    m_frames_warning += frame.verdict == Verdict::Warning ? 1 : 0;
    return frame;
}

} // namespace modestack::metrics
