// Noise variance of surface points from their residuals (see surface_noise.h).
#include "core/objectspace/surface_noise.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>

namespace modestack::objectspace {

std::vector<double> surface_noise_variance(const SurfaceNeighbours& neighbours, double window,
                                           const std::vector<SurfaceFrame>& frames, int channels,
                                           int kept_modes)
{
    const std::int64_t count = neighbours.count();
    const int frame_count = static_cast<int>(frames.size());
    const std::size_t ch = static_cast<std::size_t>(channels);
    auto residual = [&](int t, std::int64_t q, std::size_t c) {
        return static_cast<double>(frames[t].noisy[q * ch + c]) - frames[t].values[q * ch + c];
    };
    // Per point: Σ_t d², scaled to s² × frames by 1 / (1 + 1/k).
    std::vector<double> energy(static_cast<std::size_t>(count) * ch, 0.0), noise(energy.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            const std::int64_t* ids = neighbours.ids(p);
            const int others = neighbours.count_within(p, window) - 1;
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
    // Pooled over the window, per degree of freedom.
    const double degrees = std::max(1, frame_count - kept_modes);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            const std::int64_t* ids = neighbours.ids(p);
            const int members = neighbours.count_within(p, window);
            for (std::size_t c = 0; c < ch; ++c) {
                double sum = 0;
                for (int n = 0; n < members; ++n)
                    sum += energy[ids[n] * ch + c];
                noise[p * ch + c] = sum / members / degrees;
            }
        }
    });
    return noise;
}

} // namespace modestack::objectspace
