// Noise variance of surface points from their residuals (see surface_noise.h).
#include "core/objectspace/surface_noise.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>

namespace modestack::objectspace {

std::vector<double> surface_noise_variance(const SurfaceNeighbours& neighbours,
                                           const std::vector<int>& members, const SurfaceShot& shot,
                                           int kept_modes)
{
    const std::int64_t count = neighbours.count();
    const int frame_count = shot.frames();
    const std::size_t ch = static_cast<std::size_t>(shot.channels);
    // Per point: Σ_t d², a frame at a time (each point's sum in frame order:
    // the same bits for any thread count), scaled to s² × frames by 1 / (1 + 1/k).
    std::vector<double> energy(static_cast<std::size_t>(count) * ch, 0.0), noise(energy.size(), 0.0);
    std::vector<float> noisy(static_cast<std::size_t>(shot.frame_values));
    for (int t = 0; t < frame_count; ++t) {
        shot.read_noisy(t, noisy.data());
        const float* rebuilt = shot.rebuilt[static_cast<std::size_t>(t)];
        auto residual = [&](std::int64_t q, std::size_t c) {
            return static_cast<double>(noisy[q * ch + c]) - rebuilt[q * ch + c];
        };
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count),
                          [&](const tbb::blocked_range<std::int64_t>& range) {
                              for (std::int64_t p = range.begin(); p != range.end(); ++p) {
                                  const std::int32_t* ids = neighbours.ids(p);
                                  const int others = members[p] - 1;
                                  for (std::size_t c = 0; c < ch; ++c) {
                                      double around = 0;
                                      for (std::int64_t n = 1; n <= others; ++n)
                                          around += residual(ids[n], c);
                                      const double d = residual(p, c) - (others > 0 ? around / others : 0.0);
                                      energy[p * ch + c] += d * d;
                                  }
                              }
                          });
    }
    for (std::int64_t p = 0; p < count; ++p) {
        const int others = members[p] - 1;
        for (std::size_t c = 0; c < ch; ++c)
            energy[p * ch + c] /= others > 0 ? 1.0 + 1.0 / others : 1.0;
    }
    // Pooled over the window, per degree of freedom.
    const double degrees = std::max(1, frame_count - kept_modes);
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
        for (std::int64_t p = range.begin(); p != range.end(); ++p) {
            const std::int32_t* ids = neighbours.ids(p);
            for (std::size_t c = 0; c < ch; ++c) {
                double sum = 0;
                for (int n = 0; n < members[p]; ++n)
                    sum += energy[ids[n] * ch + c];
                noise[p * ch + c] = sum / members[p] / degrees;
            }
        }
    });
    return noise;
}

} // namespace modestack::objectspace
