// How the engine walks a shot within a memory budget: either the selected
// channels of the whole shot fit (read once and kept; pass 2 then works on
// windows of it), or the shot is streamed in bands of scanlines, read once for
// the statistics and again for each later pass. Memory then grows with
// width × frames × band height (plus one byte per sample of the image for the
// outlier marks), never with height × frames. Band heights are multiples of
// kChunkRows so that the Gram matrix is fed the same fixed row chunks either
// way, which keeps results bit-identical. Where even a kChunkRows band with its
// halo does not fit, the passes with a halo walk shorter bands (slower: each
// re-reads its halo) while the statistics keep whole chunks.
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstdint>

namespace modestack::denoise {

/// Image rows per Gram chunk; every band height but the last is a multiple.
inline constexpr int kChunkRows = 16;

/// Largest pass-2 band of a kept shot: larger bands only use more memory (the
/// halo's recomputed rows are already a small share at this height).
inline constexpr int kMaxKeptBandRows = 128;

/// What pass 2 holds for a band besides its input, counted in images of one
/// float per sample (width × channels per image row).
struct PassNeeds {
    int halo_rows = 0;        ///< rows read above and below a band (the widest spatial reach)
    int sigma_halo_rows = 0;  ///< of those, the rows sigma's residual needs rebuilt for every frame
    int halo_images = 0;      ///< images over the band with its halo (coefficients, the filter's guide)
    int band_images = 0;      ///< images over the band's own rows (filtered modes, gains, workers' scratch)
    /// Images over the band with its halo that only the mode filter's survey holds
    /// (its [pixel][mode] copy of the coefficients). The survey ends before pass 2's
    /// own buffers exist, so a band needs the larger of the two, not their sum.
    int survey_images = 0;
    std::int64_t source_row_bytes = 0;  ///< what the source keeps per row of a streamed band
    /// Rows beyond a band that pass 2 rebuilds for the estimator choice
    /// (estimator_choice.h); > 0 also keeps each frame's sigma apart, since the
    /// choice reads the band's input rows after sigma, and holds the input rows
    /// the choice reads as the source gives them (about as many rows again),
    /// one frame's per worker (`choice_workers` of them).
    int choice_rows = 0;
    int choice_workers = 0;
    /// Several layers' runs (layer_runs.h): beside each layer's own rows, the
    /// rows decoded for all of them are held for a band of every frame (and, of
    /// a kept shot, for `shared_frames` whole frames while it is read), and so
    /// are the band's rebuilt values and sigma until every layer has given them.
    bool shared_rows = false;
    int shared_frames = 0;
};

/// The chosen way through a shot.
struct BandPlan {
    bool in_memory = false;  ///< whole shot kept after one read
    int band_rows = 0;       ///< rows per band of the later passes (and of every read when streaming)
    /// Rows per band of the passes that read a halo around it (the mode filter's
    /// survey and pass 2): band_rows, or fewer (down to 1) when even a kChunkRows
    /// band with its halo does not fit. Their bits do not depend on the band
    /// height; the Gram's chunks do, so the statistics keep band_rows.
    int halo_band_rows = 0;
    int halo_rows = 0;       ///< extra rows read above and below a band in pass 2
    /// A streamed band may keep the rows it shares with the last one
    /// (ShotStream::band_with_halo); not in a run of several layers, whose
    /// shared decoded rows serve each band's later reads of its rows.
    bool rolls = false;
    std::int64_t estimated_bytes = 0;  ///< working memory of the plan
    std::int64_t budget_bytes = 0;     ///< the budget it was made for
};

/// Plans for `max_memory_bytes` of working memory. Throws modestack::Error
/// (usage) when even a minimal band does not fit.
BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, const PassNeeds& needs);

/// Bytes of one image row of the input of every frame (a read band or the kept shot).
std::int64_t input_bytes_per_row(const ShotShape& shape);
/// Bytes pass 2 holds for a band of `band_rows` rows, its input aside: the
/// unfiltered rebuild of every frame over the band and sigma's halo, sigma's
/// scratch, the images of `needs` and, when `sigma_apart`, each frame's sigma of
/// the band's rows (a streamed band keeps sigma in its own input rows instead);
/// or, when larger, what the survey holds in their place (PassNeeds::survey_images).
std::int64_t pass_two_bytes(const ShotShape& shape, const PassNeeds& needs, int band_rows, bool sigma_apart);

}  // namespace modestack::denoise
