#include "core/denoise/transform.h"

#include "core/common/error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace modestack::denoise {
namespace {

// Parses the number after "log:" or "pow:"; throws naming the whole value.
double parse_parameter(const std::string& text, const std::string& number)
{
    try {
        size_t used = 0;
        double value = std::stod(number, &used);
        if (used == number.size() && std::isfinite(value))
            return value;
    } catch (const std::exception&) {
    }
    throw usage_error(fmt::format("--transform '{}': the parameter after ':' must be a number", text));
}

double sign_power(double value, double exponent)
{
    return std::copysign(std::pow(std::fabs(value), exponent), value);
}

} // namespace

Transform parse_transform(const std::string& text)
{
    Transform transform;
    if (text == "none")
        return transform;
    if (text == "log" || text.rfind("log:", 0) == 0) {
        transform.kind = TransformKind::Log;
        if (text.size() > 3) {
            transform.epsilon_fraction = parse_parameter(text, text.substr(4));
            if (transform.epsilon_fraction <= 0)
                throw usage_error(
                    fmt::format("--transform '{}': the log offset fraction must be above 0", text));
        }
        return transform;
    }
    if (text.rfind("pow:", 0) == 0) {
        transform.kind = TransformKind::Power;
        transform.gamma = parse_parameter(text, text.substr(4));
        // Below 1 the map would expand the range and its inverse's slope is infinite at 0.
        if (transform.gamma < 1 || transform.gamma > 8)
            throw usage_error(fmt::format("--transform '{}': G must be between 1 and 8", text));
        return transform;
    }
    throw usage_error(fmt::format("--transform '{}' is not one of none, log, log:FRACTION, pow:G", text));
}

std::string transform_name(const Transform& transform)
{
    switch (transform.kind) {
    case TransformKind::Log:
        return "log";
    case TransformKind::Power:
        return fmt::format("pow:{}", transform.gamma);
    default:
        return "none";
    }
}

void apply_forward(const Transform& transform, float* values, std::size_t count)
{
    const double epsilon = transform.epsilon, floor = transform.epsilon / 1000,
                 exponent = 1.0 / transform.gamma;
    for (std::size_t i = 0; i < count; ++i) {
        const double x = values[i];
        if (!std::isfinite(x))
            continue;
        if (transform.kind == TransformKind::Log)
            values[i] = static_cast<float>(std::log(std::max(x + epsilon, floor)));
        else if (transform.kind == TransformKind::Power)
            values[i] = static_cast<float>(sign_power(x, exponent));
    }
}

void apply_inverse(const Transform& transform, float* values, std::size_t count)
{
    for (std::size_t i = 0; i < count; ++i) {
        const double y = values[i];
        if (transform.kind == TransformKind::Log)
            values[i] = static_cast<float>(std::exp(y) - transform.epsilon);
        else if (transform.kind == TransformKind::Power)
            values[i] = static_cast<float>(sign_power(y, transform.gamma));
    }
}

void map_sigma_back(const Transform& transform, const float* transformed, float* sigma, std::size_t count)
{
    for (std::size_t i = 0; i < count; ++i) {
        const double y = transformed[i];
        double slope = 1.0;
        if (transform.kind == TransformKind::Log)
            slope = std::exp(y);
        else if (transform.kind == TransformKind::Power)
            slope = transform.gamma * std::pow(std::fabs(y), transform.gamma - 1);
        sigma[i] = static_cast<float>(sigma[i] * slope);
    }
}

float transformed_zero(const Transform& transform)
{
    float zero = 0.0f;
    apply_forward(transform, &zero, 1);
    return zero;
}

double sample_shot_mean(FrameSource& source, int max_frames)
{
    const ShotShape shape = source.shape();
    const int count = std::max(1, std::min(max_frames, shape.frames));
    std::vector<float> frame(static_cast<std::size_t>(shape.width) * shape.height * shape.channels);
    double sum = 0;
    std::int64_t finite = 0;
    for (int k = 0; k < count; ++k) {
        // Evenly spread, first and last frame included when count > 1.
        const int index =
            count == 1 ? 0
                       : static_cast<int>((static_cast<std::int64_t>(k) * (shape.frames - 1)) / (count - 1));
        source.read_rows(index, 0, shape.height, frame.data(), nullptr);
        for (float value : frame)
            if (std::isfinite(value)) {
                sum += value;
                ++finite;
            }
    }
    return finite > 0 ? sum / static_cast<double>(finite) : 0.0;
}

void TransformSource::read_rows(int frame_index, int row_begin, int row_end, float* destination,
                                PassThroughRows* pass_through)
{
    m_inner.read_rows(frame_index, row_begin, row_end, destination, pass_through);
    const ShotShape shape = m_inner.shape();
    apply_forward(m_transform, destination,
                  static_cast<std::size_t>(row_end - row_begin) * shape.width * shape.channels);
}

void InverseTransformSink::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt,
                                      const float* sigma, const PassThroughRows* pass_through)
{
    const std::size_t count =
        static_cast<std::size_t>(row_end - row_begin) * m_shape.width * m_shape.channels;
    // Called concurrently for different frames: scratch per thread.
    thread_local std::vector<float> values, errors;
    values.assign(rebuilt, rebuilt + count);
    errors.assign(sigma, sigma + count);
    map_sigma_back(m_transform, values.data(), errors.data(), count);
    apply_inverse(m_transform, values.data(), count);
    m_inner.write_rows(frame_index, row_begin, row_end, values.data(), errors.data(), pass_through);
}

} // namespace modestack::denoise
