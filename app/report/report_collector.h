// The --report collector: decorators around the denoise engine's source and
// sink that keep what the HTML report shows without a second read of the shot.
// The source side keeps a box-downsampled copy of every frame (the stack the
// rank slider's preview modes are projected from) and larger copies of the few
// shown frames; the sink side keeps the shown frames' rebuilt values and sigma
// and sums every frame's estimated error. The engine reads a row several times
// (pass 1, the mode filter's survey, pass 2) and frames concurrently: each row
// of a frame is taken on its first read only (the source hands out the same
// values every time), under a per-frame lock.
#pragma once

#include "app/report/report_data.h"
#include "core/denoise/frame_stream.h"

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace modestack::app::report {

/// Sizes and frames the collector keeps.
struct CollectorOptions {
    /// Largest width of the rank slider's images: N_max noise-like images of this
    /// size are most of the page (1080p: 240 × 135, about 130 kB each in base64).
    int preview_width = 240;
    int panel_width = 640;  ///< largest width of the side-by-side images
    /// Largest size of the downsampled stack of all frames; the preview width
    /// shrinks to fit it (long shots).
    std::int64_t max_stack_bytes = std::int64_t(256) << 20;
    std::vector<int> shown_indices;  ///< frames shown side by side (indices)
};

/// Box-downsampled first three channels of one image, filled row by row.
class BoxImage {
public:
    BoxImage() = default;
    /// An image of `width` × `height` pixels of `channels` channels seen through boxes of `factor`.
    BoxImage(int width, int height, int channels, int factor);
    /// Adds full-resolution row `row` ([x][channel]); non-finite values count as 0.
    void add_row(int row, const float* values);
    /// The box means (partial boxes at the right and bottom edges average what they hold).
    LinearImage mean() const;
    int small_width() const { return m_small_width; }
    int small_height() const { return m_small_height; }
    const std::vector<float>& sums() const { return m_sums; }

private:
    int m_width = 0, m_height = 0, m_channels = 0, m_factor = 1;
    int m_small_width = 0, m_small_height = 0;
    std::vector<float> m_sums;  // small_width × small_height × 3
};

/// The box size that makes `width` at most `largest` pixels wide (at least 1).
int box_factor(int width, int largest);

/// The label of the panel that shows which estimator each pixel was taken from.
extern const char* const kEstimatorMapLabel;

/// Keeps what the report needs while the engine runs between source() and sink().
class Collector {
public:
    /// `source` and `sink` must outlive this object.
    Collector(denoise::FrameSource& source, denoise::FrameSink& sink, CollectorOptions options);
    ~Collector();
    denoise::FrameSource& source();
    denoise::FrameSink& sink();

    int preview_factor() const { return m_preview_factor; }
    int panel_factor() const { return m_panel_factor; }
    const std::vector<int>& shown_indices() const { return m_options.shown_indices; }

    /// Per frame, the mean over the shown channels of σ² / (rebuilt² + 0.01): the
    /// relMSE (refine/equal_quality.h) sigma predicts; NaN for frames never written.
    std::vector<double> estimated_error() const;
    /// c_j = Σ_t X_small(first + t) · modes[j][t] for every j (mean images of the stack).
    std::vector<LinearImage> coefficient_images(int first, const std::vector<std::vector<double>>& modes) const;
    /// Noisy, denoised and sigma panels of the shown frames (sigma: the mean over the
    /// shown channels, grey).
    std::vector<ShownFrame> shown_frames(const std::vector<int>& frame_numbers) const;

    /// Called by the decorators.
    void take_source_rows(int frame_index, int row_begin, int row_end, const float* rows);
    void take_sink_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma);
    void take_choice_rows(int frame_index, int row_begin, int row_end, const std::uint8_t* chosen);

private:
    struct Shown {
        BoxImage noisy, denoised, sigma;
        BoxImage chosen;               // the estimator map's colours
        std::vector<bool> rows_chosen; // taken already
        bool any_chosen = false;
    };
    class Source;
    class Sink;
    CollectorOptions m_options;
    denoise::ShotShape m_shape;
    int m_preview_factor = 1, m_panel_factor = 1;
    std::vector<BoxImage> m_stack;                 // per frame, preview size
    std::vector<std::vector<bool>> m_rows_read;    // per frame, per row: taken already
    std::vector<std::vector<bool>> m_rows_written; // the same for the sink
    std::vector<double> m_error_sums;              // per frame
    std::vector<std::int64_t> m_error_samples;     // per frame
    std::vector<int> m_shown_slot;                 // per frame: index in m_shown or -1
    std::vector<Shown> m_shown;
    std::unique_ptr<std::mutex[]> m_frame_locks;
    std::unique_ptr<Source> m_source;
    std::unique_ptr<Sink> m_sink;
};

}  // namespace modestack::app::report
