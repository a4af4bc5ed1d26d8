// A per-pixel, fractional number of modes ([0090]): `--rank-map`. The global N
// (the mode filter's SURE survey, or --rank) is right on average, but a mode can
// carry light in one part of the frame only (a lamp, a moving shadow) and too
// little over the whole frame for the global rule to keep it. Per pixel p and
// filtered mode j, the window of (2r+1)² pixels around p estimates the mode's
// local signal energy S_j = Σ c_j² − s_j Σ v − 2·spread (s_j the mode's noise
// scale, v the per-sample noise variance: mode_filter.h; spread = s_j Σ v √(2/n)
// over the window's n samples, so that a pure-noise mode rarely counts) and the
// noise the filtered mode keeps there, K_j = s_j Σ v · gain_j(p). Keeping the
// mode lowers the expected error by S_j − K_j, so the pixel keeps the prefix of
// modes 1..n, n ≥ N, that maximises Σ_{j≤n} (S_j − K_j). The next mode enters
// with the weight that minimises its own error, w = S/(S + K) in [0, 1] (a mode
// scaled by w costs (1 − w)² S + w² K): the pixel's rank is n + w, and a
// fractional rank blends the rebuilds with n and n + 1 modes. Pixels may use up
// to `extra_modes` modes beyond N (those the survey filtered).
//
// Why never fewer than N: letting pixels drop modes below N (the same rule from
// n ≥ 1) raised relMSE by 3-11 % on three of our four scenes and 5 % on the
// Cycles shot (2026-11-24): where a kept mode's local signal is weak, dropping it
// is a bias the filtered mode's small kept noise does not repay.
#pragma once

#include "core/denoise/mode_filter.h"
#include "core/lowrank/band.h"

#include <cstdint>
#include <vector>

namespace modestack::denoise {

/// Knobs of --rank-map.
struct RankMapOptions {
    bool enabled = false;
    /// Modes beyond N a pixel may use (capped by the modes the filter surveyed).
    int extra_modes = 4;
    /// Radius of the window of the local signal and noise estimates, in pixels.
    int radius = 3;
};

/// What the map holds over the whole image.
struct RankMapSummary {
    int largest_rank = 0;   ///< modes a pixel could use
    double mean = 0, smallest = 0, largest = 0;
    /// Pixels whose rank lies in [k, k + 1), k = 0..largest_rank (the last bin: exactly largest_rank).
    std::vector<std::int64_t> histogram;
    /// Adds a band's ranks (any order of bands gives the same summary).
    void add(const std::vector<float>& ranks);
    /// Fills mean from the sums; call once after the last add.
    void finish();

private:
    std::int64_t m_pixels = 0;
    std::int64_t m_micro_rank_sum = 0;  // Σ round(rank · 10⁶): exact, order-free
    bool m_any = false;
};

/// For rows [valid_y0, valid_y1) of a band: the blend weight of each of the
/// first `modes` filtered modes at each pixel, keeping at least `min_modes` (`weights`, [mode][valid pixel]: 1,
/// 0, or a fraction for one mode) and the pixel's rank (`ranks`, per valid
/// pixel). `coefficients` are the band's unfiltered coefficient images (at least
/// `modes`), `noise_variance` per sample as for the mode filter, `gains` the noise
/// gain of each filtered mode ([mode][valid pixel], from filter_coefficients).
void local_rank(const lowrank::BandView& coefficients, const std::vector<float>& noise_variance,
                const lowrank::ImageBandShape& shape, int valid_y0, int valid_y1, const ModeFilterPlan& plan,
                int min_modes, int modes, const std::vector<float>& gains, int radius, std::vector<float>& weights,
                std::vector<float>& ranks);

}  // namespace modestack::denoise
