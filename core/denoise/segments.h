// `denoise --segments`: a shot whose lighting changes abruptly (a light switched
// on, a cut) is not low-rank as a whole, since each lighting state needs modes of
// its own and the rebuild of one state leaks into the other. Split at the change
// and each part is denoised on its own ([0087], [0092], [0096]). This file holds
// the segment list (parsed from "1-30,31-60" or found from the data), the views
// that show the engine one segment of the shot as if it were the whole shot, and
// the loop that runs the engine once per segment.
//
// Automatic cuts come from a cheap pre-pass (one more read of the shot): each
// frame is averaged over 8×8-pixel blocks (which divides the per-pixel noise by
// 8), and the frame-to-frame distance d_t = RMS(blocks_t − blocks_{t−1}) is
// compared with its own robust level over the shot: a cut is a frame whose d_t is
// above median(d) + k · 1.4826 · MAD(d) and above ratio × median(d). Smooth motion
// gives a flat d_t; noise gives the same level everywhere.
#pragma once

#include "core/common/progress.h"
#include "core/denoise/engine.h"
#include "core/denoise/frame_stream.h"

#include <string>
#include <vector>

namespace modestack::denoise {

/// Frames [first, first + count) of the shot (indices, not frame numbers).
struct FrameSegment {
    int first = 0;
    int count = 0;
};

/// Parses "1-30,31-60" in frame numbers (`frame_numbers[t]` is the number of
/// index t): contiguous, ascending, covering every frame exactly once, each part
/// at least 3 frames. Throws a usage error naming --segments otherwise.
std::vector<FrameSegment> parse_segments(const std::string& list, const std::vector<int>& frame_numbers);

/// Settings of the automatic cut search.
struct CutSearchOptions {
    int block = 8;              ///< block size of the downsampled frames (pixels)
    double mad_factor = 8.0;    ///< k of the robust threshold
    double median_ratio = 3.0;  ///< a cut's distance is at least this many medians
    int min_segment_frames = 3; ///< shortest part a cut may leave
};

/// What the search saw and found.
struct CutSearch {
    std::vector<int> cuts;         ///< indices t where a new segment starts (ascending)
    std::vector<double> distances; ///< d_t for t = 1..F−1 (index t−1)
    double median = 0;
    double threshold = 0;
};

/// Reads every frame of `source` once (frames in parallel) and finds the cuts.
CutSearch find_cuts(FrameSource& source, const CutSearchOptions& options = {});
/// The cuts as segments covering `frames` frames.
std::vector<FrameSegment> segments_from_cuts(const std::vector<int>& cuts, int frames);

/// Frames [first, first + count) of `inner`, as a shot of their own.
class FrameRangeSource : public FrameSource {
public:
    FrameRangeSource(FrameSource& inner, FrameSegment segment) : m_inner(inner), m_segment(segment) {}
    ShotShape shape() const override;
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override
    {
        m_inner.read_rows(m_segment.first + frame_index, row_begin, row_end, destination, pass_through);
    }
    std::int64_t band_bytes_per_row() const override;
    int auxiliary_channels(Auxiliary kind) const override { return m_inner.auxiliary_channels(kind); }
    void read_auxiliary_rows(Auxiliary kind, int frame_index, int row_begin, int row_end, float* destination) override
    {
        m_inner.read_auxiliary_rows(kind, m_segment.first + frame_index, row_begin, row_end, destination);
    }
    int layer_variance_channels(int layer) const override { return m_inner.layer_variance_channels(layer); }
    void read_layer_variance_rows(int layer, int frame_index, int row_begin, int row_end,
                                  float* destination) override
    {
        m_inner.read_layer_variance_rows(layer, m_segment.first + frame_index, row_begin, row_end,
                                         destination);
    }

private:
    FrameSource& m_inner;
    FrameSegment m_segment;
};

/// Writes a segment's frames to their place in `inner`. Only the first segment
/// forwards begin() (the inner sink opens every output once).
class FrameRangeSink : public FrameSink {
public:
    FrameRangeSink(FrameSink& inner, FrameSegment segment, bool forward_begin)
        : m_inner(inner), m_segment(segment), m_forward_begin(forward_begin)
    {
    }
    void begin(const RebuildStart& start) override
    {
        if (m_forward_begin)
            m_inner.begin(start);
    }
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const PassThroughRows* pass_through) override
    {
        m_inner.write_rows(m_segment.first + frame_index, row_begin, row_end, rebuilt, sigma, pass_through);
    }
    void write_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen) override
    {
        m_inner.write_choice_rows(m_segment.first + frame_index, row_begin, row_end, chosen);
    }

private:
    FrameSink& m_inner;
    FrameSegment m_segment;
    bool m_forward_begin;
};

/// Runs the engine once per segment, in order; one report per segment. Throws
/// a usage error when the sink wants spatial modes (they differ per segment).
std::vector<Report> run_segments(FrameSource& source, FrameSink& sink, const Settings& settings,
                                 const std::vector<FrameSegment>& segments, Progress& progress);

/// One report for the whole shot: the first segment's, with the frame count,
/// passes, counts and times of all segments added up and no temporal modes.
Report merge_reports(const std::vector<Report>& reports);

} // namespace modestack::denoise
