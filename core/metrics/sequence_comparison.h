// Streaming comparison of a test sequence against its reference, frame by
// frame in time order: per-frame error sums and verdicts, and the shot's totals.
// Only the previous frame of each sequence is kept (for the flicker term), so
// memory does not grow with the number of frames. Shot figures are pooled
// over every value of every frame (e.g. the shot PSNR comes from the pooled
// tonemapped MSE, not from averaging per-frame PSNRs); shot flicker pools
// frames 2..F.
#pragma once

#include "core/metrics/image_error.h"
#include "core/metrics/verdict.h"

#include <cstdint>
#include <vector>

namespace modestack::metrics {

/// The figures of one compared frame.
struct FrameComparison {
    ErrorSums sums;  ///< its error sums (flicker empty for the first frame)
    Verdict verdict; ///< idiff's verdict for this frame
};

/// Accumulates a comparison over a shot.
class SequenceComparison {
public:
    /// Frames of `pixel_count` pixels with `channels` interleaved float values each.
    SequenceComparison(std::int64_t pixel_count, int channels, const PixelThresholds& thresholds,
                       const VerdictRule& rule);

    /// Compares the next frame (time order). `test` and `reference` hold
    /// pixel_count × channels values; they are copied for the next frame's flicker.
    FrameComparison add_frame(const float* test, const float* reference);

    /// Sums over every frame added so far, merged in frame order.
    const ErrorSums& shot() const { return m_shot; }
    /// Worst verdict of the frames added so far (Pass before any frame).
    Verdict verdict() const { return m_verdict; }
    int frames() const { return m_frames; }
    /// Frames added so far whose verdict was Failure / Warning.
    int frames_failing() const { return m_frames_failing; }
    int frames_warning() const { return m_frames_warning; }

private:
    std::int64_t m_pixel_count;
    int m_channels;
    PixelThresholds m_thresholds;
    VerdictRule m_rule;
    std::vector<float> m_previous_test;
    std::vector<float> m_previous_reference;
    ErrorSums m_shot;
    Verdict m_verdict = Verdict::Pass;
    int m_frames = 0;
    int m_frames_failing = 0;
    int m_frames_warning = 0;
};

} // namespace modestack::metrics
