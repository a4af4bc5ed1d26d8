#include "app/run_quality.h"

#include "core/refine/equal_quality.h"

#include <cmath>

namespace modestack::app {

using Json = nlohmann::ordered_json;

Json quality_summary(const scene::FrameSpan& highlight_frames, const std::vector<int>& frames,
                     const std::vector<std::vector<std::vector<double>>>& errors, const Json& seconds,
                     RenderTiming noisy, RenderTiming reference)
{
    const char* kVersions[] = {"noisy", "denoised", "refined"};
    const double our_seconds = seconds["total"].get<double>();
    // Time model t(s) = t0 + k·s per frame from the noisy and reference renders.
    double frame_count = static_cast<double>(frames.size());
    double t_noisy = noisy.seconds / frame_count;
    double t_reference = reference.seconds / frame_count;
    refine::TimeModel time_model =
        refine::fit_time_model(noisy.spp, t_noisy, reference.spp, t_reference);
    Json quality;
    quality["reference_spp"] = reference.spp;
    quality["time_model"] = {{"t0_seconds", time_model.t0}, {"k_seconds_per_spp", time_model.k}};
    auto mean_of = [](const std::vector<double>& values, const std::vector<bool>& keep) {
        double sum = 0;
        int count = 0;
        for (size_t t = 0; t < values.size(); ++t)
            if (keep[t]) {
                sum += values[t];
                ++count;
            }
        return count ? sum / count : 0.0;
    };
    std::vector<bool> all(frames.size(), true), highlighted(frames.size(), false);
    bool has_highlight = false;
    for (size_t t = 0; t < frames.size(); ++t)
        if (highlight_frames.contains(frames[t]))
            highlighted[t] = has_highlight = true;
    const char* kLayers[] = {"DiffInd", "beauty"};
    for (int layer = 0; layer < 2; ++layer) {
        Json entry;
        double noisy_error = mean_of(errors[layer][0], all);
        double c = refine::noise_constant(noisy_error, noisy.spp, reference.spp);
        entry["c"] = c;
        for (int v = 0; v < 3; ++v) {
            double error = mean_of(errors[layer][v], all);
            entry["relmse"][kVersions[v]] = error;
            if (has_highlight)
                entry["relmse_crossing_frames"][kVersions[v]] = mean_of(errors[layer][v], highlighted);
            double equivalent = refine::equivalent_spp(error, c, reference.spp);
            bool finite = std::isfinite(equivalent);
            entry["equivalent_spp"][kVersions[v]] = finite ? Json(equivalent) : Json();
            entry["beyond_reference"][kVersions[v]] = !finite || equivalent > reference.spp;
            double brute_force = frame_count * time_model.seconds(equivalent);
            double our_time = v == 0 ? seconds["render"].get<double>()
                              : v == 1
                                  ? seconds["render"].get<double>() + seconds["denoise"].get<double>()
                                  : our_seconds;
            entry["speedup"][kVersions[v]] = finite ? Json(brute_force / our_time) : Json();
        }
        entry["note"] = "beyond_reference: the error is within a few times the reference's own, so the "
                        "equivalent spp (null: not measurable at all) and speed-up are extrapolated; "
                        "render a reference with more spp";
        quality[kLayers[layer]] = entry;
    }
    quality["per_frame"] = Json::array();
    for (size_t t = 0; t < frames.size(); ++t)
        quality["per_frame"].push_back({{"frame", frames[t]},
                                        {"DiffInd", {errors[0][0][t], errors[0][1][t], errors[0][2][t]}},
                                        {"beauty", {errors[1][0][t], errors[1][1][t], errors[1][2][t]}}});
    return quality;
}

}  // namespace modestack::app
