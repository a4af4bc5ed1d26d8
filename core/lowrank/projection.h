// The rebuild of a band from the first N temporal modes: each row x (one sample
// over F frames) becomes V_N V_Nᵀ x, its least-squares fit by the modes ([0056]).
// The same product split in two gives the spatial coefficients c = xᵀ V_N (the
// spatial modes ps(·, j) scaled by σ_j), which the caller may filter spatially
// ([0052]) before rebuilding from them. Rows are independent and split into fixed
// tiles, so the output is bit-identical for any thread count.
#pragma once

#include "core/lowrank/band.h"

#include <Eigen/Core>

namespace modestack::lowrank {

/// Writes V_N V_Nᵀ x for every row x of `in` into `out` (same rows and frames; `out`
/// may not alias `in`). `temporal_n` is F×N (the first N columns of Basis::temporal).
/// Throws modestack::Error (internal) on mismatched shapes.
void project_band(const BandView& in, const Eigen::MatrixXd& temporal_n, MutableBandView out);

/// Writes the coefficients c = xᵀ V_N of every row into `coefficients`, a band with
/// the same rows and one "frame" per mode (coefficients.frames == N): mode j of row i is
/// coefficients.data[j * coefficients.frame_stride + i], i.e. one spatial image per mode.
void project_coefficients(const BandView& in, const Eigen::MatrixXd& temporal_n,
                          MutableBandView coefficients);

/// Rebuilds x̂ = V_N c for every row from its coefficients (layout of
/// project_coefficients) into `out` (F frames). Each value is summed in mode
/// order, so rebuilding some frames (rows of temporal_n) gives their bits of all.
void rebuild_from_coefficients(const BandView& coefficients, const Eigen::MatrixXd& temporal_n,
                               MutableBandView out);

} // namespace modestack::lowrank
