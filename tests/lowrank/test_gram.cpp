// Gram route: exact recovery of a low-rank sequence, the 3/F noise reduction of a
// rank-3 rebuild, merging, and bit-identical results for 1 and 2 threads.
#include "core/lowrank/basis.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/projection.h"
#include "tests/lowrank/synthetic.h"

#include <doctest/doctest.h>
#include <tbb/task_arena.h>

#include <cstring>

using namespace modestack::lowrank;
using namespace modestack::lowrank::testing;

namespace {

Basis gram_basis(const FrameMatrix& matrix, std::int64_t band_rows)
{
    GramAccumulator accumulator(matrix.frames);
    for (std::int64_t row0 = 0; row0 < matrix.rows; row0 += band_rows)
        accumulator.add(matrix.band(row0, std::min(band_rows, matrix.rows - row0)));
    return basis_from_gram(accumulator);
}

FrameMatrix rebuild(const FrameMatrix& matrix, const Basis& basis, int kept_modes)
{
    FrameMatrix out(matrix.rows, matrix.frames);
    project_band(matrix.view(), basis.temporal.leftCols(kept_modes), out.mutable_view());
    return out;
}

} // namespace

TEST_CASE("Gram route recovers an exact rank-3 sequence")
{
    const FrameMatrix clean = low_rank_matrix(20000, 24, {3.0, 1.5, 0.8}, 11);
    const Basis basis = gram_basis(clean, 5000);
    CHECK(basis.rows == 20000);
    CHECK(basis.modes() == 24);
    for (int j = 1; j < basis.modes(); ++j)
        CHECK(basis.singular_values(j) <= basis.singular_values(j - 1));
    // Float storage of X leaves rounding-level modes only.
    const double tail_ratio = basis.singular_values(3) / basis.singular_values(0);
    MESSAGE("sigma_4 / sigma_1 = " << tail_ratio);
    CHECK(tail_ratio < 1e-6);
    // V is orthonormal and its sign convention holds.
    const Eigen::MatrixXd gram_of_v = basis.temporal.transpose() * basis.temporal;
    CHECK((gram_of_v - Eigen::MatrixXd::Identity(24, 24)).norm() < 1e-12);
    for (int j = 0; j < 24; ++j)
        CHECK(basis.temporal.col(j).maxCoeff() >= -basis.temporal.col(j).minCoeff());

    const FrameMatrix rebuilt = rebuild(clean, basis, 3);
    const double relative = std::sqrt(squared_distance(rebuilt, clean) / squared_norm(clean));
    MESSAGE("rank-3 rebuild relative error = " << relative);
    CHECK(relative < 1e-5);
}

TEST_CASE("rank-3 rebuild keeps a fraction 3/F of i.i.d. noise, falling with F")
{
    double previous = 1.0;
    for (int frames : {12, 24, 48}) {
        const FrameMatrix clean = low_rank_matrix(20000, frames, {3.0, 1.5, 0.8}, 21);
        FrameMatrix noisy = clean;
        add_gaussian_noise(noisy, 0.3, 22);
        const Basis basis = gram_basis(noisy, 8192);
        const FrameMatrix rebuilt = rebuild(noisy, basis, 3);
        const double ratio = squared_distance(rebuilt, clean) / squared_distance(noisy, clean);
        const double expected = 3.0 / frames;
        MESSAGE("F = " << frames << ": error ratio " << ratio << ", expected " << expected);
        CHECK(ratio == doctest::Approx(expected).epsilon(0.2));
        CHECK(ratio < previous);
        previous = ratio;
    }
}

TEST_CASE("merging accumulators equals accumulating everything")
{
    FrameMatrix noisy = low_rank_matrix(9000, 16, {2.0, 1.0}, 31);
    add_gaussian_noise(noisy, 0.1, 32);
    GramAccumulator whole(16), first(16), second(16);
    whole.add(noisy.view());
    first.add(noisy.band(0, 4000));
    second.add(noisy.band(4000, 5000));
    first.merge(second);
    CHECK(first.rows() == whole.rows());
    CHECK((first.gram() - whole.gram()).norm() <= 1e-12 * whole.gram().norm());
    CHECK((first.frame_sum() - whole.frame_sum()).norm() <= 1e-12 * whole.frame_sum().norm());
    CHECK((whole.gram() - whole.gram().transpose()).norm() == 0.0);
    // The two interleaved halves add up to the whole; 5 tiles: 0, 2, 4 (4904 rows) are
    // even, 1, 3 (4096 rows) odd, and their energies are in about that proportion.
    CHECK((whole.half_gram(0) + whole.half_gram(1) - whole.gram()).norm() <= 1e-12 * whole.gram().norm());
    CHECK(whole.half_gram(0).trace() / whole.half_gram(1).trace() ==
          doctest::Approx(4904.0 / 4096).epsilon(0.05));
    CHECK_THROWS(first.merge(GramAccumulator(15)));
}

TEST_CASE("Gram accumulation and projection are bit-identical with 1 and 2 threads")
{
    FrameMatrix noisy = low_rank_matrix(30000, 20, {2.0, 1.0, 0.5}, 41);
    add_gaussian_noise(noisy, 0.2, 42);
    auto run = [&](int threads, Eigen::MatrixXd& gram, FrameMatrix& rebuilt) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            GramAccumulator accumulator(noisy.frames);
            accumulator.add(noisy.view());
            gram = accumulator.gram();
            const Basis basis = basis_from_gram(accumulator);
            project_band(noisy.view(), basis.temporal.leftCols(3), rebuilt.mutable_view());
        });
    };
    Eigen::MatrixXd gram_one, gram_two;
    FrameMatrix rebuilt_one(noisy.rows, noisy.frames), rebuilt_two(noisy.rows, noisy.frames);
    run(1, gram_one, rebuilt_one);
    run(2, gram_two, rebuilt_two);
    CHECK(std::memcmp(gram_one.data(), gram_two.data(), sizeof(double) * gram_one.size()) == 0);
    CHECK(std::memcmp(rebuilt_one.data.data(), rebuilt_two.data.data(),
                      sizeof(float) * rebuilt_one.data.size()) == 0);
}

TEST_CASE("coefficients then rebuild equals the direct projection")
{
    FrameMatrix noisy = low_rank_matrix(5000, 12, {2.0, 1.0}, 51);
    add_gaussian_noise(noisy, 0.1, 52);
    const Basis basis = gram_basis(noisy, 5000);
    const Eigen::MatrixXd temporal = basis.temporal.leftCols(2);
    FrameMatrix coefficients(noisy.rows, 2);
    project_coefficients(noisy.view(), temporal, coefficients.mutable_view());
    // The coefficients of a row are the spatial modes scaled by σ: Σ_i c_ij² = σ_j².
    for (int j = 0; j < 2; ++j) {
        double energy = 0;
        for (std::int64_t i = 0; i < noisy.rows; ++i)
            energy += double(coefficients.at(i, j)) * coefficients.at(i, j);
        CHECK(std::sqrt(energy) == doctest::Approx(basis.singular_values(j)).epsilon(1e-5));
    }
    FrameMatrix from_coefficients(noisy.rows, noisy.frames), direct(noisy.rows, noisy.frames);
    rebuild_from_coefficients(coefficients.view(), temporal, from_coefficients.mutable_view());
    project_band(noisy.view(), temporal, direct.mutable_view());
    CHECK(std::sqrt(squared_distance(from_coefficients, direct) / squared_norm(direct)) < 1e-6);
}
