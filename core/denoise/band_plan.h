// How the engine walks a shot within a memory budget: either the selected
// channels of the whole shot fit (read once and kept), or the shot is streamed
// in bands of scanlines, read once for the statistics and once more to rebuild.
// Memory then grows with width × frames × band height, never with the image
// height. Band heights are multiples of kChunkRows so that the Gram matrix is fed
// the same fixed row chunks either way, which keeps results bit-identical.
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstdint>

namespace modestack::denoise {

/// Image rows per Gram chunk; every band height but the last is a multiple.
inline constexpr int kChunkRows = 16;

/// The chosen way through a shot.
struct BandPlan {
    bool in_memory = false;  ///< whole shot kept after one read
    int band_rows = 0;       ///< rows per band (whole height when in memory)
    int halo_rows = 0;       ///< extra rows read above and below a band in pass 2
    std::int64_t estimated_bytes = 0;  ///< working memory of the plan
};

/// Plans for `max_memory_bytes` of working memory. `halo_rows` is what pass 2
/// needs around a band (spatial pooling of sigma); `modes` the largest N.
/// Throws modestack::Error (usage) when even a minimal band does not fit.
BandPlan plan_bands(const ShotShape& shape, std::int64_t max_memory_bytes, int halo_rows, int modes);

/// Bytes of working memory for one image row of every frame in pass 2.
std::int64_t bytes_per_band_row(const ShotShape& shape, int modes);

}  // namespace modestack::denoise
