// Randomized SVD: agreement with the exact Gram route, pass count, reproducible
// Gaussian start matrix, and bit-identical results for 1 and 2 threads.
#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/projection.h"
#include "core/lowrank/randomized_svd.h"
#include "tests/lowrank/synthetic.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <cstring>

using namespace modestack::lowrank;
using namespace modestack::lowrank::testing;
using modestack::Progress;

TEST_CASE("randomized SVD agrees with the Gram route")
{
    FrameMatrix noisy = low_rank_matrix(20000, 40, {3.0, 1.5, 0.8}, 61);
    add_gaussian_noise(noisy, 0.3, 62);
    GramAccumulator accumulator(noisy.frames);
    accumulator.add(noisy.view());
    const Basis exact = basis_from_gram(accumulator);

    RandomizedSvdOptions options;
    const Basis randomized =
        randomized_svd(pass_over(noisy, 6000), noisy.frames, 3, options, Progress::silent());
    CHECK(randomized.passes == options.power_iterations + 2);
    CHECK(randomized.rows == noisy.rows);
    CHECK(randomized.modes() == 3);
    CHECK((randomized.frame_energy - exact.frame_energy).norm() <= 1e-12 * exact.frame_energy.norm());
    for (int j = 0; j < 3; ++j) {
        const double relative = std::abs(randomized.singular_values(j) / exact.singular_values(j) - 1);
        MESSAGE("sigma_" << j + 1 << " relative difference " << relative);
        CHECK(relative < 1e-6);
    }
    FrameMatrix from_exact(noisy.rows, noisy.frames), from_randomized(noisy.rows, noisy.frames);
    project_band(noisy.view(), exact.temporal.leftCols(3), from_exact.mutable_view());
    project_band(noisy.view(), randomized.temporal, from_randomized.mutable_view());
    const double projection_difference =
        std::sqrt(squared_distance(from_exact, from_randomized) / squared_norm(from_exact));
    MESSAGE("projection relative difference " << projection_difference);
    CHECK(projection_difference < 1e-5);
    // Same sign convention: the modes themselves agree, not only their span.
    CHECK((randomized.temporal - exact.temporal.leftCols(3)).norm() < 1e-5);
}

TEST_CASE("randomized SVD is exact when the sketch spans every frame")
{
    FrameMatrix noisy = low_rank_matrix(3000, 8, {2.0, 1.0}, 71);
    add_gaussian_noise(noisy, 0.2, 72);
    GramAccumulator accumulator(noisy.frames);
    accumulator.add(noisy.view());
    const Basis exact = basis_from_gram(accumulator);
    RandomizedSvdOptions options;
    options.power_iterations = 0;
    const Basis randomized = randomized_svd(pass_over(noisy, 1000), 8, 8, options, Progress::silent());
    CHECK(randomized.passes == 2);
    for (int j = 0; j < 8; ++j)
        CHECK(randomized.singular_values(j) == doctest::Approx(exact.singular_values(j)).epsilon(1e-9));
    CHECK_THROWS_AS(randomized_svd(pass_over(noisy, 1000), 8, 9, options, Progress::silent()),
                    modestack::Error);
    CHECK_THROWS_AS(randomized_svd(pass_over(noisy, 1000), 8, 0, options, Progress::silent()),
                    modestack::Error);
}

TEST_CASE("randomized SVD is bit-identical with 1 and 2 threads")
{
    FrameMatrix noisy = low_rank_matrix(25000, 16, {2.0, 1.0, 0.5}, 81);
    add_gaussian_noise(noisy, 0.2, 82);
    auto run = [&](int threads) {
        Basis basis;
        tbb::task_arena arena(threads);
        arena.execute([&] {
            basis = randomized_svd(pass_over(noisy, 10000), noisy.frames, 3, RandomizedSvdOptions{},
                                   Progress::silent());
        });
        return basis;
    };
    const Basis one = run(1);
    const Basis two = run(2);
    CHECK(std::memcmp(one.temporal.data(), two.temporal.data(), sizeof(double) * one.temporal.size()) == 0);
    CHECK(std::memcmp(one.singular_values.data(), two.singular_values.data(), sizeof(double) * 3) == 0);
}

TEST_CASE("Gaussian start matrix is reproducible and standard normal")
{
    const Eigen::MatrixXd first = gaussian_matrix(1000, 50, 7);
    const Eigen::MatrixXd again = gaussian_matrix(1000, 50, 7);
    const Eigen::MatrixXd other = gaussian_matrix(1000, 50, 8);
    CHECK(first == again);
    CHECK(first != other);
    const double mean = first.mean();
    const double variance = first.array().square().mean() - mean * mean;
    const double fourth = first.array().pow(4).mean();
    CHECK(std::abs(mean) < 0.01);         // standard error 0.0045
    CHECK(std::abs(variance - 1) < 0.02); // standard error 0.0063
    CHECK(std::abs(fourth - 3) < 0.15);   // Gaussian kurtosis, standard error ≈ 0.044
}
