#include "core/lowrank/tiles.h"

#include "core/common/avx2_clones.h"
#include "core/common/error.h"
#include "core/common/progress.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

namespace modestack::lowrank {
namespace {
// Tiles whose partials are held at once: bounds memory to kTilesPerBatch F×k
// matrices whatever the band size, without changing the order of the sum.
constexpr std::int64_t kTilesPerBatch = 64;
} // namespace

std::int64_t tile_count(std::int64_t rows)
{
    return (rows + kTileRows - 1) / kTileRows;
}

MODESTACK_AVX2_CLONES void copy_tile(const BandView& band, std::int64_t row0, std::int64_t count, Eigen::MatrixXd& tile)
{
    tile.resize(count, band.frames);
    for (int f = 0; f < band.frames; ++f) {
        const float* source = band.data + f * band.frame_stride + row0;
        double* target = tile.col(f).data();
        for (std::int64_t i = 0; i < count; ++i)
            target[i] = static_cast<double>(source[i]);
    }
}

void reduce_tiles_in_order(std::int64_t rows,
                           const std::function<void(std::int64_t row0, std::int64_t count,
                                                    Eigen::MatrixXd& partial)>& partial_of_tile,
                           Eigen::MatrixXd& sum)
{
    const std::int64_t tiles = tile_count(rows);
    std::vector<Eigen::MatrixXd> partials(static_cast<std::size_t>(std::min(tiles, kTilesPerBatch)));
    for (std::int64_t first = 0; first < tiles; first += kTilesPerBatch) {
        throw_if_cancelled();
        const std::int64_t last = std::min(tiles, first + kTilesPerBatch);
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(first, last, 1),
                          [&](const tbb::blocked_range<std::int64_t>& range) {
                              for (std::int64_t tile = range.begin(); tile != range.end(); ++tile) {
                                  const std::int64_t row0 = tile * kTileRows;
                                  partial_of_tile(row0, std::min(kTileRows, rows - row0),
                                                  partials[static_cast<std::size_t>(tile - first)]);
                              }
                          });
        for (std::int64_t tile = first; tile < last; ++tile)
            sum += partials[static_cast<std::size_t>(tile - first)];
    }
}

void for_each_tile(std::int64_t rows, const std::function<void(std::int64_t row0, std::int64_t count)>& work)
{
    throw_if_cancelled();
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, tile_count(rows), 1),
                      [&](const tbb::blocked_range<std::int64_t>& range) {
                          for (std::int64_t tile = range.begin(); tile != range.end(); ++tile) {
                              const std::int64_t row0 = tile * kTileRows;
                              work(row0, std::min(kTileRows, rows - row0));
                          }
                      });
}

} // namespace modestack::lowrank
