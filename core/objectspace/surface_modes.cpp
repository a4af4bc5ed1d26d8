// The rebuilt points on the rebuild's temporal basis (see surface_modes.h).
#include "core/objectspace/surface_modes.h"

#include <Eigen/SVD>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <stdexcept>

namespace modestack::objectspace {

SurfaceModes project_on_weights(const std::vector<std::vector<double>>& weights, const SurfaceShot& shot,
                                std::int64_t points)
{
    const int frame_count = shot.frames(), channels = shot.channels;
    Eigen::MatrixXd matrix(frame_count, static_cast<Eigen::Index>(weights.size()));
    for (std::size_t j = 0; j < weights.size(); ++j) {
        if (static_cast<int>(weights[j].size()) != frame_count)
            throw std::invalid_argument("project_on_weights: the weights and the frames differ in length");
        for (int t = 0; t < frame_count; ++t)
            matrix(t, static_cast<Eigen::Index>(j)) = weights[j][static_cast<std::size_t>(t)];
    }
    SurfaceModes modes;
    modes.channels = channels;
    modes.basis.resize(frame_count, 0);
    if (matrix.cols() > 0) {
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(matrix, Eigen::ComputeThinU);
        const Eigen::VectorXd& singular = svd.singularValues();
        Eigen::Index rank = 0;
        while (rank < singular.size() && singular[rank] > 1e-9 * singular[0])
            ++rank;
        modes.basis = svd.matrixU().leftCols(rank);
    }
    const int n = modes.count();
    const std::size_t ch = static_cast<std::size_t>(channels);
    modes.coefficients.assign(static_cast<std::size_t>(points) * n * ch, 0.0);
    tbb::parallel_for(
        tbb::blocked_range<std::int64_t>(0, points), [&](const tbb::blocked_range<std::int64_t>& range) {
            for (std::int64_t p = range.begin(); p != range.end(); ++p) {
                double* coefficient = modes.coefficients.data() + static_cast<std::size_t>(p) * n * ch;
                for (int t = 0; t < frame_count; ++t)
                    for (int j = 0; j < n; ++j)
                        for (std::size_t c = 0; c < ch; ++c)
                            coefficient[j * ch + c] +=
                                modes.basis(t, j) * shot.rebuilt[static_cast<std::size_t>(t)][p * ch + c];
            }
        });
    return modes;
}

} // namespace modestack::objectspace
