// Rank rules: PRESS finds the true rank under Gaussian and heavy-tailed noise, the
// variance rule matches a hand-computed example, the noise floor finds the rank of
// low-rank + white noise and measures the noise level, --rank is validated.
#include "core/common/error.h"
#include "core/lowrank/basis.h"
#include "core/lowrank/gram.h"
#include "core/lowrank/rank_rule.h"
#include "tests/lowrank/synthetic.h"

#include <doctest/doctest.h>

#include <random>

using namespace modestack::lowrank;
using namespace modestack::lowrank::testing;

namespace {

const std::vector<double> kAmplitudes = {3.0, 2.0, 1.5, 1.0, 0.7};

std::vector<double> amplitudes_for(int kept_modes)
{
    return std::vector<double>(kAmplitudes.begin(), kAmplitudes.begin() + kept_modes);
}

Basis basis_of(const FrameMatrix& matrix)
{
    GramAccumulator accumulator(matrix.frames);
    accumulator.add(matrix.view());
    return basis_from_gram(accumulator);
}

// Adds rare positive spikes of `height` with probability `probability` per sample.
void add_spikes(FrameMatrix& matrix, double probability, double height, std::uint64_t seed)
{
    std::mt19937_64 engine(seed);
    const std::uint64_t limit = static_cast<std::uint64_t>(probability * 18446744073709551615.0);
    for (float& value : matrix.data)
        if (engine() < limit)
            value += static_cast<float>(height);
}

// A basis whose V is the identity: σ_j² are the frame energies, so u(N) is easy by hand.
Basis diagonal_basis(const std::vector<double>& energies)
{
    const int frames = static_cast<int>(energies.size());
    Basis basis;
    basis.temporal = Eigen::MatrixXd::Identity(frames, frames);
    basis.singular_values.resize(frames);
    basis.frame_energy.resize(frames);
    for (int j = 0; j < frames; ++j) {
        basis.singular_values(j) = std::sqrt(energies[static_cast<std::size_t>(j)]);
        basis.frame_energy(j) = energies[static_cast<std::size_t>(j)];
    }
    basis.rows = 1000;
    return basis;
}

} // namespace

TEST_CASE("press picks the true rank on low-rank + Gaussian noise")
{
    for (int kept_modes : {2, 3, 5})
        for (double noise : {0.05, 0.3, 0.8}) {
            FrameMatrix noisy = low_rank_matrix(20000, 24, amplitudes_for(kept_modes), 100 + kept_modes);
            add_gaussian_noise(noisy, noise, 200 + kept_modes);
            const Basis basis = basis_of(noisy);
            const RankDecision decision = rank_by_press(basis);
            // Without the half Grams (as from the randomized SVD) press is not cross-fitted.
            Basis plain = basis;
            plain.half_gram = {};
            CHECK(rank_by_press(plain).kept_modes == kept_modes);
            MESSAGE("rank " << kept_modes << ", noise " << noise << ": press chose " << decision.kept_modes
                            << " (" << decision.reasoning << ")");
            CHECK(decision.kept_modes == kept_modes);
            CHECK(decision.rule == "press");
            CHECK(decision.score.size() == 23); // N = 0..F-2
            CHECK(decision.score[0] == doctest::Approx(1.0));
            CHECK(decision.noise_sigma == doctest::Approx(noise).epsilon(0.05));
        }
}

TEST_CASE("press keeps at most true rank + 1 under heavy-tailed noise")
{
    for (int kept_modes : {2, 3, 5}) {
        FrameMatrix noisy = low_rank_matrix(20000, 24, amplitudes_for(kept_modes), 300 + kept_modes);
        add_gaussian_noise(noisy, 0.3, 400 + kept_modes);
        add_spikes(noisy, 1e-3, 50 * 0.3, 500 + kept_modes);
        const Basis basis = basis_of(noisy);
        const RankDecision press = rank_by_press(basis);
        const RankDecision floor = rank_by_noise_floor(basis, basis.rows);
        MESSAGE("rank " << kept_modes << " + 50x spikes: press chose " << press.kept_modes
                        << ", noise-floor chose " << floor.kept_modes);
        CHECK(press.kept_modes >= kept_modes);
        CHECK(press.kept_modes <= kept_modes + 1);
    }
}

TEST_CASE("cross-fitted press keeps the true rank when a few pixels are far noisier")
{
    // 0.1 % of the pixels carry 100× the noise (caustic paths, firefly-prone pixels):
    // the noise energy sits in few rows, which the plain PRESS and the Gavish–Donoho
    // threshold both take for structure.
    for (int kept_modes : {2, 3, 5}) {
        FrameMatrix noisy = low_rank_matrix(20000, 24, amplitudes_for(kept_modes), 300 + kept_modes);
        const Eigen::MatrixXd noise = gaussian_matrix(20000, 24, 400 + kept_modes);
        std::mt19937_64 engine(500 + kept_modes);
        for (std::int64_t i = 0; i < noisy.rows; ++i) {
            const double deviation = engine() % 1000 == 0 ? 30.0 : 0.3;
            for (int t = 0; t < 24; ++t)
                noisy.at(i, t) += static_cast<float>(deviation * noise(i, t));
        }
        const Basis basis = basis_of(noisy);
        Basis plain = basis;
        plain.half_gram = {};
        const int cross_fitted = rank_by_press(basis).kept_modes;
        const int not_cross_fitted = rank_by_press(plain).kept_modes;
        const int noise_floor = rank_by_noise_floor(basis, basis.rows).kept_modes;
        MESSAGE("rank " << kept_modes << " + noisy pixels: press chose " << cross_fitted << ", plain press "
                        << not_cross_fitted << ", noise-floor " << noise_floor);
        CHECK(cross_fitted >= kept_modes);
        CHECK(cross_fitted <= kept_modes + 1);
        CHECK(not_cross_fitted > kept_modes + 1); // the case is hard: proves the test discriminates
    }
}

TEST_CASE("cross-fitted PRESS on identical halves equals the plain PRESS")
{
    FrameMatrix noisy = low_rank_matrix(6000, 16, {2.0, 1.0, 0.5}, 1001);
    add_gaussian_noise(noisy, 0.3, 1002);
    const Basis basis = basis_of(noisy);
    const std::vector<double> plain = press_curve(basis, 14);
    const std::vector<double> crossed = cross_fitted_press_curve(basis.half_gram[0] + basis.half_gram[1],
                                                                 basis.half_gram[0] + basis.half_gram[1], 14);
    for (int n = 0; n <= 14; ++n)
        CHECK(crossed[static_cast<std::size_t>(n)] ==
              doctest::Approx(plain[static_cast<std::size_t>(n)]).epsilon(1e-8));
}

TEST_CASE("a mode living on one frame is penalised by press")
{
    // Rank 2 plus one frame made very bright everywhere: the third mode is that frame
    // alone (h_t ≈ 1 there), which cannot be predicted from the other frames.
    FrameMatrix noisy = low_rank_matrix(20000, 24, {3.0, 2.0}, 601);
    add_gaussian_noise(noisy, 0.3, 602);
    const Eigen::MatrixXd flash = gaussian_matrix(20000, 1, 603);
    for (std::int64_t i = 0; i < noisy.rows; ++i)
        noisy.at(i, 7) += static_cast<float>(4.0 * flash(i, 0));
    const Basis basis = basis_of(noisy);
    CHECK(leverages(basis, 3)(7) > 0.99);
    const RankDecision decision = rank_by_press(basis);
    MESSAGE("firefly frame: press chose " << decision.kept_modes << ", variance rule "
                                          << rank_by_variance(basis).kept_modes);
    CHECK(decision.kept_modes == 2);
}

TEST_CASE("variance rule reproduces a hand-computed example")
{
    // Energies sum to 100: u(N) = 1, .5, .2, .08, .04, .015, .006, .002, 0.
    const Basis basis = diagonal_basis({50, 30, 12, 4, 2.5, 0.9, 0.4, 0.2});
    const RankDecision by_default = rank_by_variance(basis);
    CHECK(by_default.score[3] == doctest::Approx(0.08));
    CHECK(by_default.score[5] == doctest::Approx(0.015));
    // u(4) = .04 ≤ .05 but the step to 5 is .025 > .01; u(5) = .015 and the step is .009.
    CHECK(by_default.kept_modes == 5);
    CHECK(rank_by_variance(basis, 0.05, 0.03).kept_modes == 4);
    CHECK(rank_by_variance(basis, 0.10, 0.05).kept_modes == 3);
    // Nothing qualifies: keep every mode below F.
    CHECK(rank_by_variance(basis, 0.001, 0.0001).kept_modes == 7);
    RankRuleOptions options;
    options.rule = RankRule::Variance;
    CHECK(choose_rank(basis, options).kept_modes == 5);
}

TEST_CASE("noise-floor finds the rank of low-rank + white noise")
{
    for (int kept_modes : {2, 3, 5}) {
        FrameMatrix noisy = low_rank_matrix(20000, 40, amplitudes_for(kept_modes), 700 + kept_modes);
        add_gaussian_noise(noisy, 0.5, 800 + kept_modes);
        const Basis basis = basis_of(noisy);
        const RankDecision decision = rank_by_noise_floor(basis, basis.rows);
        MESSAGE("noise-floor: rank " << kept_modes << " chose " << decision.kept_modes << ", noise sigma "
                                     << decision.noise_sigma << " (true 0.5)");
        CHECK(decision.kept_modes == kept_modes);
        CHECK(decision.noise_sigma == doctest::Approx(0.5).epsilon(0.03));
        CHECK(basis.singular_values(kept_modes - 1) > decision.noise_floor);
        CHECK(basis.singular_values(kept_modes) < decision.noise_floor);
    }
    // Pure white noise: nothing above the floor (the rule still returns 1).
    FrameMatrix noise_only(20000, 40);
    add_gaussian_noise(noise_only, 1.0, 900);
    const Basis basis = basis_of(noise_only);
    const RankDecision decision = rank_by_noise_floor(basis, basis.rows);
    CHECK(basis.singular_values(0) < decision.noise_floor);
    CHECK(decision.kept_modes == 1);
}

TEST_CASE("Marchenko-Pastur median agrees with Gavish-Donoho's omega")
{
    // β → 0: the law concentrates at 1.
    CHECK(marchenko_pastur_median(1e-6) == doctest::Approx(1.0).epsilon(1e-3));
    // ω(β) = λ*(β) / sqrt(μ_β) (Gavish & Donoho 2014); their cubic fit of ω is good to
    // about 1 %, so the numerical median must reproduce it.
    for (double beta : {0.05, 0.2, 0.5, 1.0}) {
        const double lambda =
            std::sqrt(2 * (beta + 1) + 8 * beta / (beta + 1 + std::sqrt(beta * beta + 14 * beta + 1)));
        const double omega_fit = 0.56 * beta * beta * beta - 0.95 * beta * beta + 1.82 * beta + 1.43;
        const double omega = lambda / std::sqrt(marchenko_pastur_median(beta));
        MESSAGE("beta " << beta << ": omega " << omega << ", cubic fit " << omega_fit);
        CHECK(omega == doctest::Approx(omega_fit).epsilon(0.01));
    }
}

TEST_CASE("fixed rank is validated")
{
    const Basis basis = diagonal_basis({50, 30, 12, 4, 2.5, 0.9, 0.4, 0.2});
    CHECK(rank_fixed(basis, 3).kept_modes == 3);
    CHECK(rank_fixed(basis, 7).kept_modes == 7);
    for (int bad : {0, -1, 8, 100}) {
        try {
            rank_fixed(basis, bad);
            FAIL("rank " << bad << " accepted");
        } catch (const modestack::Error& error) {
            CHECK(error.kind() == modestack::ErrorKind::Usage);
            CHECK(std::string(error.what()).find("--rank") != std::string::npos);
        }
    }
    CHECK(parse_rank_rule("noise-floor") == RankRule::NoiseFloor);
    CHECK_THROWS_AS(parse_rank_rule("magic"), modestack::Error);
}
