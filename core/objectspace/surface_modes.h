// The rebuilt points as a few coefficients each. The engine rebuilds every frame
// t of a point as Σ_j c_j B(t, j) from the same few temporal weights B
// (denoise::Report::rebuild_weights), and the surface filter is linear and the
// same in every frame, so filtering the coefficients once filters every frame:
// its cost no longer grows with the shot's length. The weights are replaced by
// an orthonormal basis Q of their span, so that a frame's filtered change is
// (Hc − c)·Q_t and its squared sum over frames is ‖Hc − c‖². Whatever of a
// rebuilt value lies outside that span (--non-negative's corrections) is kept
// as it is, unfiltered.
#pragma once

#include "core/objectspace/surface_samples.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace modestack::objectspace {

/// The rebuilt values of every point on an orthonormal temporal basis.
struct SurfaceModes {
    Eigen::MatrixXd basis;            ///< F × n, orthonormal columns spanning the rebuild weights
    std::vector<double> coefficients; ///< [point][n][channel]: Σ_t value_t Q(t, j)
    int channels = 0;
    int count() const { return static_cast<int>(basis.cols()); }
    /// Point p's coefficients, [n][channel].
    const double* of(std::int64_t p) const
    {
        return coefficients.data() + static_cast<std::size_t>(p) * basis.cols() * channels;
    }
};

/// Projects the rebuilt values of `shot`'s first `points` points on an orthonormal basis of
/// `weights` ([j][t], one entry per frame each; directions whose singular
/// value is below 1e-9 of the largest are dropped). Throws
/// std::invalid_argument for weights of another length than the frames.
SurfaceModes project_on_weights(const std::vector<std::vector<double>>& weights, const SurfaceShot& shot,
                                std::int64_t points);

} // namespace modestack::objectspace
