// How the passes of a denoise read the shot: bands of rows of every frame,
// cleaned of NaN/Inf and fireflies, either read from the source (streamed) or
// windows into the whole shot read once and kept (band_plan.h). The first read
// of a row finds its outliers and marks the samples it changed; a streamed
// shot's later reads redo only the marked ones (same input, same result). It
// counts the passes over the shot and what the cleaning found, for the report.
#pragma once

#include "core/common/progress.h"
#include "core/common/scratch_buffer.h"
#include "core/denoise/band_plan.h"
#include "core/denoise/frame_stream.h"
#include "core/denoise/stage_task.h"
#include "core/lowrank/band.h"
#include "core/lowrank/outliers.h"

#include <cstdint>
#include <vector>

namespace modestack::denoise {

/// Rows [row_begin, row_end) of every frame: sample i of frame t is data[t * stride + i].
/// Either read from the source into `storage`, or a window into the kept shot.
struct Band {
    int row_begin = 0;
    int row_end = 0;
    std::int64_t rows = 0;   ///< samples per frame: width * (row_end - row_begin) * channels
    std::int64_t stride = 0; ///< samples from one frame to the next
    float* data = nullptr;
    ScratchBuffer<float> storage; ///< read_band writes every sample
    /// Per frame, the other channels of these rows when the read kept them (pass 2
    /// of a streamed shot), for the sink's write of the same rows; empty: none.
    std::vector<PassThroughRows> pass_through;
    /// Set by band_with_halo for a caller that leaves the rows as read and
    /// cleaned: the next band of the same pass keeps the rows both share.
    bool reusable = false;

    lowrank::MutableBandView view(int frames) const { return {data, rows, frames, stride}; }
};

class ShotStream {
public:
    ShotStream(FrameSource& source, const lowrank::OutlierOptions& outliers, const BandPlan& plan,
               Progress& progress);

    const ShotShape& shape() const { return m_shape; }
    const BandPlan& plan() const { return m_plan; }
    /// Reads of the whole shot so far (a farm task's reads of its rows count as one).
    int passes() const { return m_passes; }
    /// Counts one more pass (a pass whose reads go through read_band directly).
    void count_pass() { ++m_passes; }
    /// What the cleaning of the first reads found.
    const lowrank::OutlierCounts& outliers() const { return m_outliers; }
    /// Which roughness: Σ |d| of the input as read (the estimator choice's
    /// frame factors) or Σ d² of the input cleaned of fireflies (the frame
    /// scales of the modes, which are fitted to the cleaned samples' energy:
    /// frame_weighting.h).
    enum class Roughness { AsRead, Cleaned };
    /// The input's roughness (frame_noise.h) per block of rows [row_begin,
    /// row_end) and frame, as the first reads of those rows found it (a farm
    /// statistics task's share).
    std::vector<double> roughness_blocks(int row_begin, int row_end,
                                         Roughness which = Roughness::AsRead) const;
    /// Each frame's noise factor (frame_noise.h) once the first pass has read every row.
    std::vector<double> frame_noise_factors() const;
    /// Each frame's noise scale for the modes (frame_noise.h, frame_scale_factors), then.
    std::vector<double> frame_scale_factors() const;
    std::int64_t row_samples() const { return static_cast<std::int64_t>(m_shape.width) * m_shape.channels; }
    /// How a band's rows lie in the image, for the firefly test's row neighbours.
    lowrank::ImageRowLayout row_layout() const { return {m_shape.width, m_shape.channels}; }

    /// Visits the shot in bands in a fixed order: the kept shot when it is in
    /// memory, otherwise a fresh read of each band. The first such pass counts
    /// the outliers and marks the cleaned samples.
    template <typename Visit> void for_each_band(Visit&& visit)
    {
        BandPass pass(*this);
        while (Band* band = pass.next())
            visit(*band);
    }

    /// for_each_band one band at a time, for a caller that interleaves the
    /// passes of several streams over the same files (layer_runs.h).
    class BandPass {
    public:
        explicit BandPass(ShotStream& stream);
        /// The next band (valid until the next call), or null after the last.
        Band* next();

    private:
        ShotStream& m_stream;
        bool m_first_pass = false;
        bool m_progress_open = false;
        int m_row = 0;     // first row of the next band
        int m_advance = 0; // rows of the band handed out last, counted as done at the next call
        Band m_band;
    };

    /// The kept shot, read and cleaned now when no earlier pass read it (a farm task).
    void ensure_whole_shot();
    /// A kept shot read ahead of the first pass, frames [frame_begin, frame_end)
    /// at a time, so that several layers' streams can share each decoded frame
    /// and let it go (layer_runs.h); finish_whole_shot() then cleans and counts
    /// it, and the first pass visits it without reading.
    void read_whole_frames(int frame_begin, int frame_end);
    void finish_whole_shot();
    /// Rows [row, end) of every frame with the plan's halo rows around them: a
    /// window into the kept shot, or read into `band` (`with_pass_through`: with
    /// each frame's other channels, for the writes of pass 2). With
    /// `keeps_rows` (the caller writes nothing into the band), a streamed band
    /// that follows the previous one keeps the rows they share and reads only
    /// the new ones: a band's halo is decoded once, not once per band.
    Band& band_with_halo(Band& band, int row, int end, bool with_pass_through, bool keeps_rows = false);
    /// Rows [row_begin, row_end) of one frame as the source gives them, before
    /// the firefly cleaning (the estimator choice judges the rebuild against
    /// the input itself), into `raw` [row][x][channel]; a non-finite sample
    /// takes its value in `cleaned` (a band holding those rows). A fresh read,
    /// one frame at a time: a band's choice holds one frame's rows per worker,
    /// not every frame's.
    void read_raw_frame_rows(int frame, int row_begin, int row_end, const Band& cleaned,
                             ScratchBuffer<float>& raw);
    /// A farm task's band: rows [row, end) with the plan's halo rows around them,
    /// read from the source (never the whole shot), cleaned in full.
    Band& read_task_band(Band& band, int row, int end);
    /// While set (a farm modes task), reads record the cleaned values of rows
    /// [row_begin, row_end) that differ from the files, samples counted from
    /// `first_row`; null patches: stop recording.
    void record_patches(int row_begin, int row_end, int first_row, std::vector<ModeImages::Patch>* patches)
    {
        m_patches = {row_begin, row_end, first_row, patches};
    }

    enum class Cleaning {
        Count, ///< the first read of the rows: clean, count and (streamed) mark
        Again, ///< a later read: redo the marked samples, or everything when no read marked them (a farm
               ///< task)
    };
    /// Reads rows [row_begin, row_end) of every frame (frames in parallel) into
    /// `band` and cleans them; `with_pass_through`: band.pass_through too.
    void read_band(Band& band, int row_begin, int row_end, Cleaning cleaning, bool with_pass_through = false);

private:
    void begin_pass_progress();
    /// Moves `band` on to rows [row_begin, row_end), keeping the rows it shares
    /// with them and reading the rest; false (nothing changed) when it cannot.
    bool roll_band(Band& band, int row_begin, int row_end, bool with_pass_through);
    /// A later read's cleaning (Cleaning::Again) of `rows`, whose first sample is
    /// image sample `first_sample`.
    void clean_again(const lowrank::MutableBandView& rows, std::int64_t first_sample);
    /// A first read's roughness of `band`'s rows, before its cleaning (AsRead) or after it.
    void measure_roughness(const Band& band, Roughness which);

    FrameSource& m_source;
    const lowrank::OutlierOptions& m_outlier_options;
    BandPlan m_plan;
    Progress& m_progress;
    ShotShape m_shape;
    int m_passes = 0;
    lowrank::OutlierCounts m_outliers;
    std::vector<double> m_row_roughness;         // [row][frame], by the first read of each row
    std::vector<double> m_row_cleaned_roughness; // Σ d² after its cleaning
    Band m_whole;                        // the kept shot, when it fits in memory
    bool m_whole_read_ahead = false;     // read and cleaned by read_whole_frames and finish_whole_shot
    // Streaming: 1 for each sample whose row (over frames) the outlier cleaning changed.
    std::vector<std::uint8_t> m_cleaned_samples;
    struct PatchRows {
        int row_begin = 0, row_end = 0, first_row = 0;
        std::vector<ModeImages::Patch>* patches = nullptr;
    } m_patches;
};

} // namespace modestack::denoise
