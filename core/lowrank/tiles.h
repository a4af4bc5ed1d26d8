// Fixed row tiles and in-order reductions, the one place that decides how the
// low-rank code splits a band among TBB workers. Every band is cut into tiles of
// kTileRows rows from its first row; tiles run in parallel, and their partial
// results are added in tile-index order, so a sum over a band is bit-identical for
// any thread count (it depends only on how the caller cut X into bands).
#pragma once

#include "core/lowrank/band.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>

namespace modestack::lowrank {

/// Rows per tile: big enough for efficient small matrix products, small enough
/// that a double copy of a tile (kTileRows × frames) stays in cache-sized memory.
inline constexpr std::int64_t kTileRows = 2048;

/// Number of kTileRows tiles that cover `rows` rows.
std::int64_t tile_count(std::int64_t rows);

/// Copies rows [row0, row0 + count) of `band` into `tile` (count × frames, double).
void copy_tile(const BandView& band, std::int64_t row0, std::int64_t count, Eigen::MatrixXd& tile);

/// Computes one partial matrix per tile of `rows` rows in parallel with
/// `partial_of_tile(row0, count, partial)` (which must assign `partial` fully) and
/// adds the partials to `sum` in tile order. Throws modestack::Error when a cancel
/// was requested (modestack::cancel_requested()).
void reduce_tiles_in_order(std::int64_t rows,
                           const std::function<void(std::int64_t row0, std::int64_t count,
                                                    Eigen::MatrixXd& partial)>& partial_of_tile,
                           Eigen::MatrixXd& sum);

/// Runs `work(row0, count)` on every tile of `rows` rows in parallel (for work whose
/// tiles write disjoint outputs). Throws modestack::Error when a cancel was requested.
void for_each_tile(std::int64_t rows, const std::function<void(std::int64_t row0, std::int64_t count)>& work);

} // namespace modestack::lowrank
