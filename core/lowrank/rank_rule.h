// Automatic choice of the number of modes N kept by the rebuild ([0053]). The
// default rule, `press`, is leave-one-frame-out cross-validation in closed form:
// it needs only the singular values, the temporal modes and the per-frame
// energies, so it works on the exact basis and on the randomized SVD's top modes;
// on the Gram route it is also cross-fitted over two halves of the pixels, which
// keeps a few very noisy pixels from buying modes of their own.
// The seed's unexplained-variance rule and a Gavish–Donoho noise-floor rule are
// kept for comparison (on real renders both keep far too many modes, see
// docs/design.md, "Estimators"); `fixed` validates a user's --rank N.
#pragma once

#include "core/lowrank/basis.h"

#include <cstdint>
#include <string>
#include <vector>

namespace modestack::lowrank {

/// The rules that choose N.
enum class RankRule { Press, Variance, NoiseFloor, Fixed };

/// The name of a rule as users write it: "press", "variance", "noise-floor", "fixed".
std::string rank_rule_name(RankRule rule);
/// Parses a rule name; throws modestack::Error (usage) listing the valid names.
RankRule parse_rank_rule(const std::string& name);

/// The outcome of a rank rule, with what a report needs to show why.
struct RankDecision {
    /// Chosen number of modes N (≥ 1).
    int kept_modes = 0;
    /// Name of the rule that chose it (rank_rule_name).
    std::string rule;
    /// One or two sentences for humans: what the rule saw and why this N.
    std::string reasoning;
    /// The rule's curve per N = 0..max (index = N); see each rule for its meaning.
    std::vector<double> score;
    /// Singular-value level of the noise: the Gavish–Donoho hard threshold
    /// ω(β)·median(σ) (or its known-noise form from the tail energy when only the top
    /// modes are available). Modes below it are indistinguishable from white noise.
    double noise_floor = 0;
    /// Estimated per-sample noise standard deviation behind noise_floor.
    double noise_sigma = 0;
};

/// Settings of choose_rank.
struct RankRuleOptions {
    RankRule rule = RankRule::Press;
    /// N for RankRule::Fixed.
    int fixed_modes = 0;
    /// Variance rule: largest unexplained-variance fraction accepted (seed's ε).
    double variance_epsilon = 0.05;
    /// Variance rule: largest drop of that fraction from N to N+1 accepted (ε_change).
    double variance_change = 0.01;
};

/// Applies options.rule to `basis` (basis.rows must be set for the noise floor).
RankDecision choose_rank(const Basis& basis, const RankRuleOptions& options);

/// PRESS(N) = Σ_t (G_tt − Σ_{j≤N} σ_j² V_tj²) / (1 − h_t)², h_t = Σ_{j≤N} V_tj²: the summed
/// squared leave-one-frame-out prediction error of a rank-N fit, for N = 0..max_rank.
std::vector<double> press_curve(const Basis& basis, int max_rank);

/// Cross-fitted PRESS for N = 0..max_rank: the modes V_A of one half of the rows
/// (gram_fit) are judged on the other half (gram_test):
/// Σ_t [(I − H_A) G_B (I − H_A)]_tt / (1 − h_A,t)², H_A = V_A,N V_A,Nᵀ. The plain PRESS
/// judges V on the rows it was fitted to, so a few very noisy pixels (noise energy
/// concentrated in few rows) each buy a mode that "predicts" them perfectly; here
/// those modes fit nothing in the other half and cost leverage instead. O(F³).
std::vector<double> cross_fitted_press_curve(const Eigen::MatrixXd& gram_fit,
                                             const Eigen::MatrixXd& gram_test, int max_rank);

/// `press`: N = argmin PRESS(N) over 1..min(F − 2, K). Uses the cross-fitted PRESS
/// summed over both directions (A→B + B→A) when basis.half_gram is set (Gram route),
/// the plain press_curve otherwise (randomized SVD). score[N] = PRESS(N) / PRESS(0)
/// (PRESS(0) = total energy). Because frame t's noise is independent of its
/// prediction from the other frames, PRESS = true error + a term independent of N; a
/// mode living on one frame (a firefly frame) has h_t → 1 and is penalised heavily.
RankDecision rank_by_press(const Basis& basis);

/// `variance` (seed [0053]): the smallest N whose unexplained variance fraction
/// u(N) = 1 − Σ_{j≤N} σ_j² / Σ_t G_tt is ≤ epsilon and whose next step u(N) − u(N+1) is
/// ≤ epsilon_change; score[N] = u(N). Defaults ε = 0.05, ε_change = 0.01 as in the seed.
/// With real render noise (10–40 % of the energy) this keeps dozens of modes.
RankDecision rank_by_variance(const Basis& basis, double epsilon = 0.05, double epsilon_change = 0.01);

/// `noise-floor`: Gavish–Donoho optimal hard threshold for unknown noise,
/// τ = ω(β)·median(σ), β = min(F, P) / max(F, P), ω(β) ≈ 0.56β³ − 0.95β² + 1.82β + 1.43;
/// N = #{σ_j > τ} (at least 1). Needs the full spectrum for the median; with only the
/// top K < F modes it estimates the noise from the tail energy instead.
/// score[N] = σ_N / τ for N ≥ 1 (score[0] = 0). `rows` is P.
RankDecision rank_by_noise_floor(const Basis& basis, std::int64_t rows);

/// `fixed`: the user's N, checked: 1 ≤ N < F and N ≤ available modes, otherwise
/// throws modestack::Error (usage) saying the valid range. score = u(N) as `variance`.
RankDecision rank_fixed(const Basis& basis, int kept_modes);

/// Median of the Marchenko–Pastur law of aspect ratio β ∈ (0, 1] (numerical).
double marchenko_pastur_median(double beta);

} // namespace modestack::lowrank
