#include "core/lowrank/rank_rule.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace modestack::lowrank {
namespace {

// Smallest 1 − h_t the PRESS rule divides by: a mode that carries one frame alone
// (h_t → 1) cannot be predicted from the other frames and must cost a lot.
constexpr double kMinimumOneMinusLeverage = 1e-9;

struct NoiseEstimate {
    double sigma = 0; // per-sample standard deviation
    double floor = 0; // singular-value threshold
};

double total_energy(const Basis& basis)
{
    return basis.frame_energy.sum();
}

// u(N) for N = 0..K: the fraction of the energy outside the first N modes.
std::vector<double> unexplained_fraction(const Basis& basis)
{
    const double total = total_energy(basis);
    std::vector<double> fraction(static_cast<std::size_t>(basis.modes()) + 1, 0.0);
    double explained = 0;
    for (int n = 0; n <= basis.modes(); ++n) {
        if (n > 0)
            explained += basis.singular_values(n - 1) * basis.singular_values(n - 1);
        fraction[static_cast<std::size_t>(n)] = total > 0 ? std::max(0.0, 1.0 - explained / total) : 0.0;
    }
    return fraction;
}

double omega_unknown_noise(double beta)
{
    return 0.56 * beta * beta * beta - 0.95 * beta * beta + 1.82 * beta + 1.43;
}

// Gavish–Donoho λ*(β): threshold / (sqrt(n) σ) when σ is known.
double lambda_known_noise(double beta)
{
    return std::sqrt(2 * (beta + 1) + 8 * beta / (beta + 1 + std::sqrt(beta * beta + 14 * beta + 1)));
}

NoiseEstimate estimate_noise(const Basis& basis, std::int64_t rows)
{
    NoiseEstimate estimate;
    const int frames = basis.frames();
    if (rows <= 0 || frames < 1 || basis.modes() < 1)
        return estimate;
    const double small_dimension = static_cast<double>(std::min<std::int64_t>(frames, rows));
    const double large_dimension = static_cast<double>(std::max<std::int64_t>(frames, rows));
    const double beta = small_dimension / large_dimension;
    const int nonzero = static_cast<int>(small_dimension);
    if (basis.modes() >= nonzero) {
        std::vector<double> values(basis.singular_values.data(), basis.singular_values.data() + nonzero);
        std::sort(values.begin(), values.end());
        const double median =
            nonzero % 2 == 1 ? values[nonzero / 2] : 0.5 * (values[nonzero / 2 - 1] + values[nonzero / 2]);
        estimate.floor = omega_unknown_noise(beta) * median;
        estimate.sigma = median / std::sqrt(large_dimension * marchenko_pastur_median(beta));
    } else {
        // Only the top modes: the energy outside them is mostly noise spread over the
        // remaining dimensions (an underestimate, since the top modes hold some noise).
        const double tail = std::max(0.0, unexplained_fraction(basis).back() * total_energy(basis));
        estimate.sigma = std::sqrt(tail / (static_cast<double>(rows) * (frames - basis.modes())));
        estimate.floor = lambda_known_noise(beta) * std::sqrt(large_dimension) * estimate.sigma;
    }
    return estimate;
}

RankDecision make_decision(RankRule rule, const Basis& basis)
{
    RankDecision decision;
    decision.rule = rank_rule_name(rule);
    const NoiseEstimate noise = estimate_noise(basis, basis.rows);
    decision.noise_floor = noise.floor;
    decision.noise_sigma = noise.sigma;
    return decision;
}

// Largest N a rule may return: fewer than F modes, and only the available ones.
int largest_rank(const Basis& basis)
{
    return std::max(1, std::min(basis.modes(), basis.frames() - 1));
}

} // namespace

std::string rank_rule_name(RankRule rule)
{
    switch (rule) {
    case RankRule::Press:
        return "press";
    case RankRule::Variance:
        return "variance";
    case RankRule::NoiseFloor:
        return "noise-floor";
    case RankRule::Fixed:
        return "fixed";
    }
    return "unknown";
}

RankRule parse_rank_rule(const std::string& name)
{
    for (RankRule rule : {RankRule::Press, RankRule::Variance, RankRule::NoiseFloor, RankRule::Fixed})
        if (name == rank_rule_name(rule))
            return rule;
    throw usage_error("unknown rank rule '" + name + "' (use press, variance, noise-floor or fixed)");
}

double marchenko_pastur_median(double beta)
{
    if (!(beta > 0 && beta <= 1))
        throw internal_error("Marchenko-Pastur median needs 0 < beta <= 1");
    const double lower = (1 - std::sqrt(beta)) * (1 - std::sqrt(beta));
    const double upper = (1 + std::sqrt(beta)) * (1 + std::sqrt(beta));
    const double half_width = 0.5 * (upper - lower);
    constexpr double kPi = 3.14159265358979323846;
    // x = lower + (upper − lower)(1 − cos θ)/2 removes the square-root end points, so the
    // trapezoid rule on θ ∈ [0, π] converges fast.
    auto density_in_theta = [&](double theta) {
        const double x = lower + half_width * (1 - std::cos(theta));
        if (lower <= 0) // β = 1: sin²θ / (1 − cos θ) = 1 + cos θ, finite at θ = 0
            return half_width * (1 + std::cos(theta)) / (2 * kPi * beta);
        const double sine = std::sin(theta);
        return half_width * half_width * sine * sine / (2 * kPi * beta * x);
    };
    constexpr int kSteps = 4000;
    const double step = kPi / kSteps;
    std::vector<double> cumulative(kSteps + 1, 0.0);
    for (int i = 1; i <= kSteps; ++i)
        cumulative[i] =
            cumulative[i - 1] + 0.5 * step * (density_in_theta((i - 1) * step) + density_in_theta(i * step));
    const double half = 0.5 * cumulative[kSteps];
    int i = 1;
    while (i < kSteps && cumulative[i] < half)
        ++i;
    const double fraction = (half - cumulative[i - 1]) / (cumulative[i] - cumulative[i - 1]);
    const double theta = (i - 1 + fraction) * step;
    return lower + half_width * (1 - std::cos(theta));
}

std::vector<double> press_curve(const Basis& basis, int max_rank)
{
    if (max_rank < 0 || max_rank > basis.modes())
        throw internal_error("press_curve: rank outside the available modes");
    const int frames = basis.frames();
    std::vector<double> curve(static_cast<std::size_t>(max_rank) + 1, 0.0);
    Eigen::VectorXd residual = basis.frame_energy; // G_tt − Σ_{j≤N} σ_j² V_tj²
    Eigen::VectorXd leverage = Eigen::VectorXd::Zero(frames);
    for (int n = 0; n <= max_rank; ++n) {
        if (n > 0) {
            const double energy = basis.singular_values(n - 1) * basis.singular_values(n - 1);
            residual -= energy * basis.temporal.col(n - 1).cwiseAbs2();
            leverage += basis.temporal.col(n - 1).cwiseAbs2();
        }
        double press = 0;
        for (int t = 0; t < frames; ++t) {
            const double one_minus = std::max(1.0 - leverage(t), kMinimumOneMinusLeverage);
            press += std::max(0.0, residual(t)) / (one_minus * one_minus);
        }
        curve[static_cast<std::size_t>(n)] = press;
    }
    return curve;
}

std::vector<double> cross_fitted_press_curve(const Eigen::MatrixXd& gram_fit,
                                             const Eigen::MatrixXd& gram_test, int max_rank)
{
    const Basis fit = basis_from_gram(gram_fit);
    const int frames = fit.frames();
    if (gram_test.rows() != frames || gram_test.cols() != frames || max_rank < 0 || max_rank > frames)
        throw internal_error("cross_fitted_press_curve: mismatched Gram matrices or rank");
    const Eigen::MatrixXd& modes = fit.temporal;
    // The test Gram in the fit's eigenbasis; the residual diagonal for N kept modes is
    // Q_N(t) = Σ_{j,k≥N} W_tj C_jk W_tk, built from N = F down to 0 one index at a time.
    const Eigen::MatrixXd coupling = modes.transpose() * gram_test * modes;
    std::vector<Eigen::VectorXd> residual(static_cast<std::size_t>(frames) + 1);
    residual[static_cast<std::size_t>(frames)] = Eigen::VectorXd::Zero(frames);
    for (int n = frames - 1; n >= 0; --n) {
        const int rest = frames - 1 - n;
        Eigen::VectorXd cross_term = Eigen::VectorXd::Zero(frames);
        if (rest > 0)
            cross_term = modes.rightCols(rest) * coupling.col(n).tail(rest);
        residual[static_cast<std::size_t>(n)] =
            residual[static_cast<std::size_t>(n) + 1] +
            (coupling(n, n) * modes.col(n).cwiseAbs2() + 2.0 * modes.col(n).cwiseProduct(cross_term));
    }
    std::vector<double> curve(static_cast<std::size_t>(max_rank) + 1, 0.0);
    Eigen::VectorXd leverage = Eigen::VectorXd::Zero(frames);
    for (int n = 0; n <= max_rank; ++n) {
        if (n > 0)
            leverage += modes.col(n - 1).cwiseAbs2();
        double press = 0;
        for (int t = 0; t < frames; ++t) {
            const double one_minus = std::max(1.0 - leverage(t), kMinimumOneMinusLeverage);
            press += std::max(0.0, residual[static_cast<std::size_t>(n)](t)) / (one_minus * one_minus);
        }
        curve[static_cast<std::size_t>(n)] = press;
    }
    return curve;
}

RankDecision rank_by_press(const Basis& basis)
{
    RankDecision decision = make_decision(RankRule::Press, basis);
    const int max_rank = std::max(1, std::min(basis.frames() - 2, basis.modes()));
    const bool cross_fitted = basis.half_gram[0].rows() == basis.frames() &&
                              basis.half_gram[1].rows() == basis.frames() && basis.half_gram[0].trace() > 0 &&
                              basis.half_gram[1].trace() > 0;
    if (cross_fitted) {
        decision.score = cross_fitted_press_curve(basis.half_gram[0], basis.half_gram[1], max_rank);
        const std::vector<double> other =
            cross_fitted_press_curve(basis.half_gram[1], basis.half_gram[0], max_rank);
        for (std::size_t n = 0; n < decision.score.size(); ++n)
            decision.score[n] += other[n];
    } else {
        decision.score = press_curve(basis, max_rank);
    }
    const double press_zero = decision.score[0];
    for (double& value : decision.score)
        value = press_zero > 0 ? value / press_zero : 0.0;
    int best = 1;
    for (int n = 2; n <= max_rank; ++n)
        if (decision.score[static_cast<std::size_t>(n)] < decision.score[static_cast<std::size_t>(best)])
            best = n;
    decision.kept_modes = best;
    const double at_best = decision.score[static_cast<std::size_t>(best)];
    auto change = [&](int n) {
        return at_best > 0 ? 100.0 * (decision.score[static_cast<std::size_t>(n)] / at_best - 1.0) : 0.0;
    };
    decision.reasoning =
        fmt::format("Leave-one-frame-out prediction error{} is lowest with {} mode{} "
                    "({:.4g} of the energy",
                    cross_fitted ? " (modes fitted on half of the pixels, tested on the other)" : "", best,
                    best == 1 ? "" : "s", at_best);
    if (best > 1)
        decision.reasoning += fmt::format("; N = {}: {:+.1f} %", best - 1, change(best - 1));
    if (best < max_rank)
        decision.reasoning += fmt::format("; N = {}: {:+.1f} %", best + 1, change(best + 1));
    decision.reasoning += ").";
    return decision;
}

RankDecision rank_by_variance(const Basis& basis, double epsilon, double epsilon_change)
{
    if (!(epsilon >= 0 && epsilon < 1) || !(epsilon_change >= 0 && epsilon_change < 1))
        throw usage_error("variance rule thresholds must lie in [0, 1)");
    RankDecision decision = make_decision(RankRule::Variance, basis);
    decision.score = unexplained_fraction(basis);
    const int limit = largest_rank(basis);
    int chosen = 0;
    for (int n = 1; n <= limit && n < basis.modes(); ++n) {
        const double here = decision.score[static_cast<std::size_t>(n)];
        const double next = decision.score[static_cast<std::size_t>(n) + 1];
        if (here <= epsilon && here - next <= epsilon_change) {
            chosen = n;
            break;
        }
    }
    if (chosen == 0) {
        decision.kept_modes = limit;
        decision.reasoning = fmt::format("No N up to {} leaves at most {:.3g} of the variance unexplained "
                                         "with a next step of at most {:.3g}; "
                                         "keeping all {} modes.",
                                         limit, epsilon, epsilon_change, limit);
    } else {
        decision.kept_modes = chosen;
        decision.reasoning = fmt::format("{} modes leave {:.3g} of the variance unexplained (limit {:.3g}) "
                                         "and one more mode would explain only "
                                         "{:.3g} more (limit {:.3g}).",
                                         chosen, decision.score[static_cast<std::size_t>(chosen)], epsilon,
                                         decision.score[static_cast<std::size_t>(chosen)] -
                                             decision.score[static_cast<std::size_t>(chosen) + 1],
                                         epsilon_change);
    }
    return decision;
}

RankDecision rank_by_noise_floor(const Basis& basis, std::int64_t rows)
{
    if (rows <= 0)
        throw internal_error("noise-floor rule needs the number of rows of X");
    RankDecision decision = make_decision(RankRule::NoiseFloor, basis);
    const NoiseEstimate noise = estimate_noise(basis, rows);
    decision.noise_floor = noise.floor;
    decision.noise_sigma = noise.sigma;
    decision.score.assign(static_cast<std::size_t>(basis.modes()) + 1, 0.0);
    int above = 0;
    for (int n = 1; n <= basis.modes(); ++n) {
        const double sigma = basis.singular_values(n - 1);
        decision.score[static_cast<std::size_t>(n)] = noise.floor > 0 ? sigma / noise.floor : 0.0;
        if (sigma > noise.floor)
            above = n;
    }
    decision.kept_modes = std::clamp(above, 1, largest_rank(basis));
    decision.reasoning = fmt::format("{} singular value{} above the noise floor {:.4g} (Gavish-Donoho "
                                     "threshold; noise sigma {:.4g} per sample).",
                                     above, above == 1 ? " lies" : "s lie", noise.floor, noise.sigma);
    return decision;
}

RankDecision rank_fixed(const Basis& basis, int kept_modes)
{
    if (kept_modes < 1 || kept_modes >= basis.frames())
        throw usage_error(fmt::format("--rank {} is out of range: it must be at least 1 and less than the "
                                      "number of frames ({})",
                                      kept_modes, basis.frames()));
    if (kept_modes > basis.modes())
        throw usage_error(
            fmt::format("--rank {} asks for more modes than were computed ({})", kept_modes, basis.modes()));
    RankDecision decision = make_decision(RankRule::Fixed, basis);
    decision.score = unexplained_fraction(basis);
    decision.kept_modes = kept_modes;
    decision.reasoning =
        fmt::format("{} modes chosen by the user; they leave {:.3g} of the variance unexplained.", kept_modes,
                    decision.score[static_cast<std::size_t>(kept_modes)]);
    return decision;
}

RankDecision choose_rank(const Basis& basis, const RankRuleOptions& options)
{
    switch (options.rule) {
    case RankRule::Press:
        return rank_by_press(basis);
    case RankRule::Variance:
        return rank_by_variance(basis, options.variance_epsilon, options.variance_change);
    case RankRule::NoiseFloor:
        return rank_by_noise_floor(basis, basis.rows);
    case RankRule::Fixed:
        return rank_fixed(basis, options.fixed_modes);
    }
    throw internal_error("unknown rank rule");
}

} // namespace modestack::lowrank
