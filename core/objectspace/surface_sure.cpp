// SURE of the surface filter's widths (see surface_sure.h).
#include "core/objectspace/surface_sure.h"

#include "core/objectspace/surface_kernel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>

namespace modestack::objectspace {
namespace {

// SURE is summed over at most this many frames, evenly spread: plenty of values to
// choose one width from, at a fraction of the cost of all frames.
constexpr int kSurveyFrames = 8;

std::vector<int> survey_frames(int frame_count)
{
    std::vector<int> survey;
    const int step = std::max(1, (frame_count + kSurveyFrames - 1) / kSurveyFrames);
    for (int t = step / 2; t < frame_count; t += step)
        survey.push_back(t);
    return survey;
}

} // namespace

std::vector<double> surface_sure_risks(const SurfaceNeighbours& neighbours, double spacing,
                                       const std::vector<double>& widths, const std::vector<double>& noise,
                                       const std::vector<SurfaceFrame>& frames, int channels)
{
    const std::int64_t count = neighbours.count();
    const int candidates = static_cast<int>(widths.size());
    const std::size_t ch = static_cast<std::size_t>(channels);
    const std::vector<int> survey = survey_frames(static_cast<int>(frames.size()));
    // Per point first, summed in point order after: the same bits for any thread count.
    std::vector<double> point_risk(static_cast<std::size_t>(count) * candidates, 0.0);
    if (candidates > 1)
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, count), [&](const tbb::blocked_range<std::int64_t>& range) {
            std::vector<double> weights;
            for (std::int64_t p = range.begin(); p != range.end(); ++p) {
                const std::int64_t* ids = neighbours.ids(p);
                double* risk = point_risk.data() + p * candidates;
                for (int k = 0; k < candidates; ++k) {
                    const bool unfiltered = widths[k] == 0;
                    if (!unfiltered)
                        gaussian_weights(neighbours, p, widths[k], spacing, weights);
                    for (int t : survey)
                        for (std::size_t c = 0; c < ch; ++c) {
                            const double own = frames[t].values[p * ch + c];
                            const double variance = noise[p * ch + c] * frames[t].leverage;
                            if (unfiltered) {
                                risk[k] += variance;
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
    std::vector<double> risks(static_cast<std::size_t>(candidates), 0.0);
    for (std::int64_t p = 0; p < count; ++p)
        for (int k = 0; k < candidates; ++k)
            risks[k] += point_risk[p * candidates + k];
    const double surveyed = static_cast<double>(count) * ch * std::max<std::size_t>(survey.size(), 1);
    for (double& risk : risks)
        risk /= surveyed;
    return risks;
}

} // namespace modestack::objectspace
