#include "core/denoise/weight_smoothing.h"

#include <algorithm>
#include <cmath>

namespace modestack::denoise {
namespace {

// e_t = v_{t+1} − 2 v_t + v_{t−1} for t = 1 .. F − 2 (index t − 1).
std::vector<double> second_differences(const std::vector<double>& values)
{
    std::vector<double> result;
    for (size_t t = 1; t + 1 < values.size(); ++t)
        result.push_back(values[t + 1] - 2.0 * values[t] + values[t - 1]);
    return result;
}

double median_of(std::vector<double> values)
{
    if (values.empty())
        return 0.0;
    const size_t middle = values.size() / 2;
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle), values.end());
    double upper = values[middle];
    if (values.size() % 2 == 1)
        return upper;
    double lower = *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle));
    return 0.5 * (lower + upper);
}

// The local linear fit of piece [begin, end) at `t` with Gaussian width `width`;
// `diagonal` receives the weight of values[t] in it.
double fit_at(const std::vector<double>& values, int begin, int end, int t, double width, double* diagonal)
{
    const int reach = static_cast<int>(std::ceil(4.0 * width));
    double s0 = 0, s1 = 0, s2 = 0, y0 = 0, y1 = 0;
    for (int k = std::max(begin, t - reach); k < std::min(end, t + reach + 1); ++k) {
        const double d = k - t, w = std::exp(-0.5 * d * d / (width * width));
        s0 += w, s1 += w * d, s2 += w * d * d;
        y0 += w * values[static_cast<size_t>(k)], y1 += w * d * values[static_cast<size_t>(k)];
    }
    const double determinant = s0 * s2 - s1 * s1;
    if (determinant <= 1e-9 * s0 * s0) {  // a piece of one frame: nothing to fit a line to
        *diagonal = 1.0 / s0;
        return y0 / s0;
    }
    *diagonal = s2 / determinant;  // w_t = 1 and d_t = 0
    return (s2 * y0 - s1 * y1) / determinant;
}

}  // namespace

double weight_noise(const std::vector<double>& values)
{
    std::vector<double> magnitudes = second_differences(values);
    for (double& e : magnitudes)
        e = std::abs(e);
    return 1.4826 * median_of(magnitudes) / std::sqrt(6.0);
}

std::vector<int> find_weight_jumps(const std::vector<double>& values, double noise, double threshold)
{
    std::vector<int> jumps;
    const std::vector<double> e = second_differences(values);
    const int frames = static_cast<int>(values.size());
    if (noise <= 0 || frames < 4)
        return jumps;
    const double limit = threshold * std::sqrt(6.0) * noise;
    // e[t − 1] is the second difference centred on frame t.
    auto centred = [&](int t) { return e[static_cast<size_t>(t - 1)]; };
    for (int start = 1; start < frames; ++start) {
        const int left = start - 1, right = start;  // the step lies between frames left and right
        bool jump;
        if (left == 0)
            jump = std::abs(centred(right)) > 1.5 * limit;
        else if (right == frames - 1)
            jump = std::abs(centred(left)) > 1.5 * limit;
        else
            jump = std::abs(centred(left)) > limit && std::abs(centred(right)) > limit &&
                   (centred(left) > 0) != (centred(right) > 0);
        if (jump)
            jumps.push_back(start);
    }
    return jumps;
}

std::vector<double> smooth_pieces(const std::vector<double>& values, double width, const std::vector<int>& breaks,
                                  double* trace)
{
    const int frames = static_cast<int>(values.size());
    if (width <= 0) {
        if (trace)
            *trace = frames;
        return values;
    }
    std::vector<double> result(values.size());
    double diagonal_sum = 0;
    std::vector<int> starts{0};
    for (int cut : breaks)
        if (cut > starts.back() && cut < frames)
            starts.push_back(cut);
    starts.push_back(frames);
    for (size_t piece = 0; piece + 1 < starts.size(); ++piece)
        for (int t = starts[piece]; t < starts[piece + 1]; ++t) {
            double diagonal = 0;
            result[static_cast<size_t>(t)] = fit_at(values, starts[piece], starts[piece + 1], t, width, &diagonal);
            diagonal_sum += diagonal;
        }
    if (trace)
        *trace = diagonal_sum;
    return result;
}

Eigen::MatrixXd smooth_temporal_weights(const Eigen::MatrixXd& weights, const WeightSmoothingOptions& options,
                                        WeightSmoothingPlan& plan)
{
    Eigen::MatrixXd smoothed = weights;
    plan.modes.clear();
    const int frames = static_cast<int>(weights.rows());
    for (Eigen::Index j = 0; j < weights.cols(); ++j) {
        std::vector<double> values(weights.col(j).data(), weights.col(j).data() + frames);
        ModeSmoothing mode;
        mode.noise = weight_noise(values);
        // Rounding alone (second differences of a straight line in double) is no noise.
        if (mode.noise <= 1e-9 * weights.col(j).norm() / std::sqrt(static_cast<double>(frames)))
            mode.noise = 0;
        mode.jumps = find_weight_jumps(values, mode.noise, options.jump_threshold);
        const double variance = mode.noise * mode.noise;
        const double unsmoothed_sure = frames * variance;  // S = I: no residual, tr = F
        double best_sure = unsmoothed_sure;
        if (variance > 0)
            for (double width : options.widths) {
                double trace = 0;
                std::vector<double> fitted = smooth_pieces(values, width, mode.jumps, &trace);
                double residual = 0;
                for (int t = 0; t < frames; ++t)
                    residual += (fitted[static_cast<size_t>(t)] - values[static_cast<size_t>(t)]) *
                                (fitted[static_cast<size_t>(t)] - values[static_cast<size_t>(t)]);
                const double sure = residual + 2.0 * variance * trace - frames * variance;
                if (sure < best_sure) {
                    best_sure = sure;
                    mode.width = width;
                }
            }
        mode.sure_gain = unsmoothed_sure - best_sure;
        if (mode.width > 0) {
            std::vector<double> fitted = smooth_pieces(values, mode.width, mode.jumps);
            for (int t = 0; t < frames; ++t)
                smoothed(t, j) = fitted[static_cast<size_t>(t)];
        }
        plan.modes.push_back(mode);
    }
    return smoothed;
}

}  // namespace modestack::denoise
