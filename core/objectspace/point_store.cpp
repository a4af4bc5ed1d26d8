// The points × frames matrix in memory (see point_store.h).
#include "core/objectspace/point_store.h"

#include <algorithm>

namespace modestack::objectspace {

KeepingSource::KeepingSource(denoise::FrameSource& inner) : ForwardingSource(inner), m_shape(inner.shape())
{
    m_rows.assign(static_cast<std::size_t>(m_shape.frames), std::vector<float>(row_values() * m_shape.height));
}

void KeepingSource::read_rows(int frame_index, int row_begin, int row_end, float* destination,
                              denoise::PassThroughRows* pass_through)
{
    m_inner.read_rows(frame_index, row_begin, row_end, destination, pass_through);
    std::copy(destination, destination + row_values() * (row_end - row_begin),
              m_rows[static_cast<std::size_t>(frame_index)].begin() + row_values() * row_begin);
}

PointStore::PointStore(denoise::ShotShape shape, bool keep_sigma) : m_shape(shape)
{
    const std::size_t values = static_cast<std::size_t>(shape.width) * shape.height * shape.channels;
    m_values.assign(static_cast<std::size_t>(shape.frames), std::vector<float>(values, 0.0f));
    if (keep_sigma)
        m_sigma = m_values;
}

void PointStore::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt,
                            const float* sigma, const denoise::PassThroughRows* /*pass_through*/)
{
    const std::size_t row_values = static_cast<std::size_t>(m_shape.width) * m_shape.channels;
    const std::size_t first = static_cast<std::size_t>(row_begin) * row_values;
    const std::size_t count = static_cast<std::size_t>(row_end - row_begin) * row_values;
    std::copy(rebuilt, rebuilt + count, m_values[static_cast<std::size_t>(frame_index)].begin() + first);
    if (!m_sigma.empty())
        std::copy(sigma, sigma + count, m_sigma[static_cast<std::size_t>(frame_index)].begin() + first);
}

} // namespace modestack::objectspace
