// SURE-chosen Gaussian filtering over surface points (see surface_filter.h).
#include "core/denoise/surface_filter.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace modestack::denoise {
namespace {

// Kernels are cut at this many sigmas (weight e^-4.5 ≈ 1 % there).
constexpr double kReachInSigmas = 3.0;
// Neighbours must face within ~25° of each other: the same surface, not the wall across a corner.
constexpr double kMinNormalCosine = 0.9;
// SURE is summed over at most this many frames, evenly spread: plenty of values to
// choose one width from, at a fraction of the cost of all frames.
constexpr int kSurveyFrames = 8;

std::int64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z)
{
    // 21 bits per axis, offset so that negative cells stay distinct.
    const std::int64_t offset = 1 << 20, mask = (1 << 21) - 1;
    return ((x + offset) & mask) << 42 | ((y + offset) & mask) << 21 | ((z + offset) & mask);
}

} // namespace

SurfaceNeighbours::SurfaceNeighbours(const SurfaceSamples& samples, double radius, double min_cosine)
{
    const std::int64_t count = samples.count();
    const float* position = samples.positions.data();
    const float* normal = samples.normals.data();
    auto cell_of = [&](std::int64_t p, int axis) {
        return static_cast<std::int64_t>(std::floor(position[3 * p + axis] / radius));
    };
    // Points sorted by cell: a cell's points are one run of `order`.
    std::vector<std::int64_t> keys(static_cast<std::size_t>(count)), order(static_cast<std::size_t>(count));
    for (std::int64_t p = 0; p < count; ++p)
        keys[p] = cell_key(cell_of(p, 0), cell_of(p, 1), cell_of(p, 2));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::int64_t a, std::int64_t b) { return keys[a] < keys[b]; });
    std::vector<std::int64_t> sorted_keys(static_cast<std::size_t>(count));
    for (std::int64_t i = 0; i < count; ++i)
        sorted_keys[i] = keys[order[i]];
    const float radius_squared = static_cast<float>(radius * radius);

    // Visits the neighbours of p in a fixed order (cells, then ids).
    auto visit = [&](std::int64_t p, auto&& take) {
        take(p, 0.0f); // itself first, whatever its normal
        const std::int64_t cx = cell_of(p, 0), cy = cell_of(p, 1), cz = cell_of(p, 2);
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz) {
                    const std::int64_t key = cell_key(cx + dx, cy + dy, cz + dz);
                    auto begin = std::lower_bound(sorted_keys.begin(), sorted_keys.end(), key);
                    for (auto it = begin; it != sorted_keys.end() && *it == key; ++it) {
                        const std::int64_t q = order[static_cast<std::size_t>(it - sorted_keys.begin())];
                        if (q == p)
                            continue;
                        float cosine = normal[3 * p] * normal[3 * q] + normal[3 * p + 1] * normal[3 * q + 1] +
                                       normal[3 * p + 2] * normal[3 * q + 2];
                        if (cosine < min_cosine)
                            continue;
                        float ex = position[3 * p] - position[3 * q], ey = position[3 * p + 1] - position[3 * q + 1],
                              ez = position[3 * p + 2] - position[3 * q + 2];
                        float distance_squared = ex * ex + ey * ey + ez * ez;
                        if (distance_squared <= radius_squared)
                            take(q, distance_squared);
                    }
                }
    };
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(count), 0);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p)
            visit(p, [&](std::int64_t, float) { ++sizes[p]; });
    });
    m_first.assign(static_cast<std::size_t>(count) + 1, 0);
    for (std::int64_t p = 0; p < count; ++p)
        m_first[p + 1] = m_first[p] + sizes[p];
    m_ids.resize(static_cast<std::size_t>(m_first.back()));
    m_distances.resize(m_ids.size());
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            std::int64_t next = m_first[p];
            visit(p, [&](std::int64_t q, float distance_squared) {
                m_ids[next] = q;
                m_distances[next++] = distance_squared;
            });
            // Nearest first (p itself stays first), so that any radius is a prefix.
            std::vector<std::pair<float, std::int64_t>> sorted;
            for (std::int64_t n = m_first[p] + 1; n < m_first[p + 1]; ++n)
                sorted.emplace_back(m_distances[n], m_ids[n]);
            std::sort(sorted.begin(), sorted.end());
            for (std::size_t n = 0; n < sorted.size(); ++n) {
                m_distances[m_first[p] + 1 + n] = sorted[n].first;
                m_ids[m_first[p] + 1 + n] = sorted[n].second;
            }
        }
    });
}

double SurfaceNeighbours::mean_size() const
{
    const std::size_t points = m_first.size() - 1;
    return points > 0 ? static_cast<double>(m_first.back()) / static_cast<double>(points) : 0.0;
}

SurfaceFilterChoice filter_surfaces(const SurfaceSamples& samples, const SurfaceFilterOptions& options, int channels,
                                    std::vector<SurfaceFrame>& frames)
{
    SurfaceFilterChoice choice;
    choice.widths.push_back(0);
    if (options.filter)
        for (double width : options.widths)
            if (width > 0)
                choice.widths.push_back(width);
    const std::int64_t count = samples.count();
    const int candidates = static_cast<int>(choice.widths.size());
    const int frame_count = static_cast<int>(frames.size());
    const std::size_t ch = static_cast<std::size_t>(channels);
    if (count == 0 || frame_count == 0 || !(samples.spacing > 0))
        throw std::invalid_argument("filter_surfaces: no points, frames or spacing");
    const double spacing = samples.spacing;
    const double window = options.window_spacings * spacing;
    const double widest = *std::max_element(choice.widths.begin(), choice.widths.end()) * spacing;
    SurfaceNeighbours neighbours(samples, std::max(kReachInSigmas * widest, window), kMinNormalCosine);
    choice.mean_neighbours = neighbours.mean_size();
    auto in_window = [&](float distance_squared) { return distance_squared <= window * window; };
    auto residual = [&](int t, std::int64_t q, std::size_t c) {
        return static_cast<double>(frames[t].noisy[q * ch + c]) - frames[t].values[q * ch + c];
    };

    // Noise variance per frame s², as confidence.h: the high-passed residual
    // d = r_p − mean of r over p's window (without p), whose variance is
    // (1 + 1/k)·s² for white noise, pooled over the window.
    std::vector<double> energy(static_cast<std::size_t>(count) * ch, 0.0), noise(energy.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            const std::int64_t* ids = neighbours.ids(p);
            const float* d2 = neighbours.distances_squared(p);
            int others = 0;
            while (others + 1 < neighbours.size(p) && in_window(d2[others + 1]))
                ++others;
            for (std::size_t c = 0; c < ch; ++c) {
                double sum = 0;
                for (int t = 0; t < frame_count; ++t) {
                    double around = 0;
                    for (std::int64_t n = 1; n <= others; ++n)
                        around += residual(t, ids[n], c);
                    double d = residual(t, p, c) - (others > 0 ? around / others : 0.0);
                    sum += d * d;
                }
                energy[p * ch + c] = sum / (others > 0 ? 1.0 + 1.0 / others : 1.0);
            }
        }
    });
    const double degrees = std::max(1, frame_count - options.rank);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            const std::int64_t* ids = neighbours.ids(p);
            const float* d2 = neighbours.distances_squared(p);
            for (std::size_t c = 0; c < ch; ++c) {
                double sum = 0;
                int members = 0;
                for (std::int64_t n = 0; n < neighbours.size(p) && in_window(d2[n]); ++n, ++members)
                    sum += energy[ids[n] * ch + c];
                noise[p * ch + c] = sum / members / degrees;
            }
        }
    });

    // SURE of each width: |Hy − y|² + 2·v·H_pp − v with v = s²·h_t.
    std::vector<int> survey;
    const int step = std::max(1, (frame_count + kSurveyFrames - 1) / kSurveyFrames);
    for (int t = step / 2; t < frame_count; t += step)
        survey.push_back(t);
    auto kernel = [&](std::int64_t p, double width, std::vector<double>& weights) {
        const float* d2 = neighbours.distances_squared(p);
        const double sigma = width * spacing, reach = kReachInSigmas * sigma;
        weights.assign(1, 1.0); // p itself
        double total = 1;
        for (std::int64_t n = 1; n < neighbours.size(p) && d2[n] <= reach * reach; ++n) {
            weights.push_back(std::exp(-0.5 * d2[n] / (sigma * sigma)));
            total += weights.back();
        }
        for (double& w : weights)
            w /= total;
    };
    std::vector<double> point_risk(static_cast<std::size_t>(count) * candidates, 0.0);
    if (candidates > 1)
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
            std::vector<double> weights;
            for (std::int64_t p = range.begin(); p != range.end(); ++p) {
                const std::int64_t* ids = neighbours.ids(p);
                double* risk = point_risk.data() + p * candidates;
                for (int k = 0; k < candidates; ++k) {
                    if (k > 0)
                        kernel(p, choice.widths[k], weights);
                    for (int t : survey)
                        for (std::size_t c = 0; c < ch; ++c) {
                            const double own = frames[t].values[p * ch + c];
                            const double variance = noise[p * ch + c] * frames[t].leverage;
                            if (k == 0) {
                                risk[0] += variance;
                                continue;
                            }
                            double filtered = 0;
                            for (std::size_t n = 0; n < weights.size(); ++n)
                                filtered += weights[n] * frames[t].values[ids[n] * ch + c];
                            risk[k] += (filtered - own) * (filtered - own) + 2 * variance * weights[0] - variance;
                        }
                }
            }
        });
    choice.risks.assign(static_cast<std::size_t>(candidates), 0.0);
    for (std::int64_t p = 0; p < count; ++p)
        for (int k = 0; k < candidates; ++k)
            choice.risks[k] += point_risk[p * candidates + k];
    const double surveyed = static_cast<double>(count) * ch * std::max<std::size_t>(survey.size(), 1);
    for (double& risk : choice.risks)
        risk /= surveyed;
    const int best = static_cast<int>(std::min_element(choice.risks.begin(), choice.risks.end()) - choice.risks.begin());
    choice.width = choice.widths[best];
    if (!options.filter)
        choice.reasoning = "off";
    else if (best == 0)
        choice.reasoning = fmt::format("none: the unfiltered values have the lowest SURE ({:.4g} per value)",
                                       choice.risks[0]);
    else
        choice.reasoning = fmt::format("Gaussian of {} spacings ({:.3g} m), SURE {:.4g} per value against {:.4g} "
                                       "unfiltered",
                                       choice.width, choice.width * spacing, choice.risks[best], choice.risks[0]);

    // Every frame: the filtered values and sigma = sqrt(Σ H² s² h_t + b_t²), with
    // b_t² = max(0, μ_t² − s²(1 − h_t)/|W|), μ_t the window's mean residual.
    tbb::parallel_for(0, frame_count, [&](int t) {
        const std::vector<float> rebuilt(frames[t].values, frames[t].values + count * ch);
        auto residual_of = [&](std::int64_t q, std::size_t c) {
            return static_cast<double>(frames[t].noisy[q * ch + c]) - rebuilt[q * ch + c];
        };
        const double h = frames[t].leverage;
        std::vector<double> weights{1.0};
        for (std::int64_t p = 0; p < count; ++p) {
            const std::int64_t* ids = neighbours.ids(p);
            const float* d2 = neighbours.distances_squared(p);
            if (best > 0)
                kernel(p, choice.width, weights);
            for (std::size_t c = 0; c < ch; ++c) {
                double filtered = 0, kept_noise = 0, mean_residual = 0;
                int members = 0;
                for (std::size_t n = 0; n < weights.size(); ++n) {
                    filtered += weights[n] * rebuilt[ids[n] * ch + c];
                    kept_noise += weights[n] * weights[n] * noise[ids[n] * ch + c] * h;
                }
                for (std::int64_t n = 0; n < neighbours.size(p) && in_window(d2[n]); ++n, ++members)
                    mean_residual += residual_of(ids[n], c);
                mean_residual /= members;
                const double bias = std::max(0.0, mean_residual * mean_residual - noise[p * ch + c] * (1 - h) / members);
                frames[t].values[p * ch + c] = static_cast<float>(filtered);
                frames[t].sigma[p * ch + c] = static_cast<float>(std::sqrt(kept_noise + bias));
            }
        }
    });
    return choice;
}

} // namespace modestack::denoise
