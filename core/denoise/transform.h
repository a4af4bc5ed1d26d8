// A nonlinear map applied to the shot before the SVD and inverted after the
// rebuild (`denoise --transform`, [0049]): log(x + ε) compresses the dynamic
// range so that bright pixels do not dominate the modes; a power x^(1/G) does the
// same more gently. The maths works on plain buffers; TransformSource and
// InverseTransformSink are thin decorators around the engine's two ends, so the
// engine itself never knows. Because the rebuild averages in the transformed
// domain, the output is biased: the inverse of a mean is not the mean of the
// inverse (for log, E[exp(Y)] = exp(E[Y] + var(Y)/2) > exp(E[Y])), so the output
// is darker than the linear rebuild where the noise is large. Sigma is mapped back
// with the delta method: σ_x ≈ |d f⁻¹/dy (ŷ)| σ_y.
#pragma once

#include "core/denoise/frame_stream.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace modestack::denoise {

/// Which map --transform applies.
enum class TransformKind { None, Log, Power };

/// A map and its parameters.
struct Transform {
    TransformKind kind = TransformKind::None;
    /// Power: the exponent G of f(x) = sign(x)|x|^(1/G) (≥ 1).
    double gamma = 1.0;
    /// Log: ε = epsilon_fraction × the shot's mean (log_epsilon). 0.1 keeps the
    /// zero pixels of a 4-spp render within a few units of the mean's logarithm.
    double epsilon_fraction = 0.1;
    /// Log: the offset ε of f(x) = log(x + ε), set from the shot by the caller.
    double epsilon = 0.0;
};

/// Parses "none", "log", "log:FRACTION" (ε as a fraction of the shot's mean,
/// > 0) or "pow:G" (1 ≤ G ≤ 8). Throws a usage error naming --transform otherwise.
Transform parse_transform(const std::string& text);
/// "none", "log" or "pow:G" as written.
std::string transform_name(const Transform& transform);

/// f(x) in place. Log: log(max(x + ε, ε / 1000)) (values below −ε are floored so
/// the logarithm stays finite). Power: sign(x)|x|^(1/G). Non-finite values pass.
void apply_forward(const Transform& transform, float* values, std::size_t count);
/// f⁻¹(y) in place. Log: exp(y) − ε. Power: sign(y)|y|^G.
void apply_inverse(const Transform& transform, float* values, std::size_t count);
/// Delta method: sigma[i] *= |d f⁻¹/dy| at transformed[i] (the rebuilt value
/// before the inverse). Log: exp(y). Power: G|y|^(G−1).
void map_sigma_back(const Transform& transform, const float* transformed, float* sigma, std::size_t count);
/// f(0): the transformed value of black (the floor of --non-negative).
float transformed_zero(const Transform& transform);

/// Mean of the finite values of up to `max_frames` frames spread evenly over the
/// shot (whole frames, read in a fixed order): the scale of log's ε.
double sample_shot_mean(FrameSource& source, int max_frames = 8);

/// A FrameSource whose rows are another's, mapped by f.
class TransformSource : public ForwardingSource {
public:
    /// `inner` must outlive this object.
    TransformSource(FrameSource& inner, const Transform& transform) : ForwardingSource(inner), m_transform(transform)
    {
    }
    void read_rows(int frame_index, int row_begin, int row_end, float* destination,
                   PassThroughRows* pass_through) override;

private:
    Transform m_transform;
};

/// A FrameSink that maps rebuilt rows back by f⁻¹ and sigma by the delta method
/// before forwarding them; spatial modes pass unchanged (transformed units).
class InverseTransformSink : public ForwardingSink {
public:
    /// `inner` must outlive this object; `shape` is the source's.
    InverseTransformSink(FrameSink& inner, const Transform& transform, ShotShape shape)
        : ForwardingSink(inner), m_transform(transform), m_shape(shape)
    {
    }
    void write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma,
                    const PassThroughRows* pass_through) override;

private:
    Transform m_transform;
    ShotShape m_shape;
};

} // namespace modestack::denoise
