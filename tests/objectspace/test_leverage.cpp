// Frame leverages: for orthonormal temporal modes (the right singular vectors of
// a random matrix) each lies in [0, 1] and they sum to N, as the diagonal of a
// rank-N projection; a mode that is one frame gives that frame all of it.
#include "core/objectspace/leverage.h"

#include <Eigen/Dense>
#include <doctest/doctest.h>

#include <vector>

using namespace modestack;

TEST_CASE("leverage: the diagonal of the projection on the kept modes, summing to N")
{
    const int frames = 30;
    const Eigen::MatrixXd data = Eigen::MatrixXd::Random(200, frames);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(data, Eigen::ComputeThinV);
    const Eigen::MatrixXd& v = svd.matrixV();
    for (int kept_modes : {1, 2, 5, frames}) {
        std::vector<std::vector<double>> modes(static_cast<std::size_t>(kept_modes));
        for (int j = 0; j < kept_modes; ++j)
            for (int t = 0; t < frames; ++t)
                modes[j].push_back(v(t, j));
        const std::vector<double> leverages = objectspace::frame_leverages(modes, frames);
        REQUIRE(leverages.size() == static_cast<std::size_t>(frames));
        const Eigen::MatrixXd projection = v.leftCols(kept_modes) * v.leftCols(kept_modes).transpose();
        double sum = 0;
        for (int t = 0; t < frames; ++t) {
            CHECK(leverages[t] >= 0);
            CHECK(leverages[t] <= 1 + 1e-12);
            CHECK(leverages[t] == doctest::Approx(projection(t, t)).epsilon(1e-12));
            sum += leverages[t];
        }
        CHECK(sum == doctest::Approx(kept_modes).epsilon(1e-12));
    }
}

TEST_CASE("leverage: a mode that is one frame gives that frame all of it, no modes none")
{
    std::vector<std::vector<double>> modes{{0, 0, 1, 0}};
    CHECK(objectspace::frame_leverages(modes, 4) == std::vector<double>{0, 0, 1, 0});
    CHECK(objectspace::frame_leverages({}, 3) == std::vector<double>{0, 0, 0});
}
