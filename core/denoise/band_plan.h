// How the engine walks a shot within a memory budget: either the selected
// channels of the whole shot fit (read once and kept; pass 2 then works on
// windows of it), or the shot is streamed in bands of scanlines, read once for
// the statistics and again for each later pass. Memory then grows with
// width × frames × band height (plus one byte per sample of the image for the
// outlier marks), never with height × frames. Band heights are multiples of
// kChunkRows so that the Gram matrix is fed the same fixed row chunks either
// way, which keeps results bit-identical.
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstdint>

namespace modestack::denoise {

/// Image rows per Gram chunk; every band height but the last is a multiple.
inline constexpr int kChunkRows = 16;

/// Largest pass-2 band of a kept shot: larger bands only use more memory (the
/// halo's recomputed rows are already a small share at this height).
inline constexpr int kMaxKeptBandRows = 128;

/// The chosen way through a shot.
struct BandPlan {
    bool in_memory = false;  ///< whole shot kept after one read
    int band_rows = 0;       ///< rows per band of the later passes (and of every read when streaming)
    int halo_rows = 0;       ///< extra rows read above and below a band in pass 2
    std::int64_t estimated_bytes = 0;  ///< working memory of the plan
    std::int64_t budget_bytes = 0;     ///< the budget it was made for
};

/// Plans for `max_memory_bytes` of working memory. `halo_rows` is what pass 2
/// needs around a band (spatial pooling of sigma); `modes` counts the extra
/// per-sample images pass 2 keeps besides the per-frame ones (coefficients,
/// filter scratch), `source_row_bytes` what the source keeps per row of a
/// streamed band (FrameSource::band_bytes_per_row). Throws modestack::Error
/// (usage) when even a minimal band does not fit.
BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, int halo_rows, int modes,
                    std::int64_t source_row_bytes = 0);

/// Bytes of one image row of the input of every frame (a read band or the kept shot).
std::int64_t input_bytes_per_row(const ShotShape& shape);
/// Bytes of pass 2's buffers per image row of a band: rebuilt and sigma for every
/// frame, a third per-frame share for sigma's noise-power scratch (which holds 16
/// frames at a time: the share leaves room for the rest of pass 2's scratch), plus
/// `modes` per-sample images.
std::int64_t work_bytes_per_row(const ShotShape& shape, int modes);

}  // namespace modestack::denoise
