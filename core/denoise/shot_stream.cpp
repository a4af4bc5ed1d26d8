#include "core/denoise/shot_stream.h"

#include "core/common/error.h"
#include "core/denoise/frame_noise.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace modestack::denoise {

ShotStream::ShotStream(FrameSource& source, const lowrank::OutlierOptions& outliers, const BandPlan& plan,
                       Progress& progress)
    : m_source(source), m_outlier_options(outliers), m_plan(plan), m_progress(progress),
      m_shape(source.shape())
{
}

ShotStream::BandPass::BandPass(ShotStream& stream) : m_stream(stream), m_first_pass(stream.m_passes == 0)
{
    ++m_stream.m_passes;
    if (m_stream.m_plan.in_memory && !m_first_pass)
        return;
    m_stream.begin_pass_progress();
    m_progress_open = true;
    if (!m_stream.m_plan.in_memory && m_first_pass)
        m_stream.m_cleaned_samples.assign(
            static_cast<size_t>(m_stream.row_samples()) * m_stream.m_shape.height, 0);
}

Band* ShotStream::BandPass::next()
{
    ShotStream& stream = m_stream;
    const int height = stream.m_shape.height;
    if (m_advance > 0) {
        stream.m_progress.advance(m_advance);
        m_advance = 0;
    }
    if (m_row >= height) {
        if (m_progress_open)
            stream.m_progress.end();
        m_progress_open = false;
        return nullptr;
    }
    if (stream.m_plan.in_memory) { // one band: the whole shot
        m_row = height;
        if (!m_first_pass || stream.m_whole_read_ahead)
            return &stream.m_whole;
        stream.read_band(stream.m_whole, 0, height, Cleaning::Count);
        m_advance = height;
        return &stream.m_whole;
    }
    const int end = std::min(height, m_row + stream.m_plan.band_rows);
    stream.read_band(m_band, m_row, end, m_first_pass ? Cleaning::Count : Cleaning::Again);
    m_advance = end - m_row;
    m_row = end;
    return &m_band;
}

void ShotStream::begin_pass_progress()
{
    m_progress.begin(fmt::format("pass {}: reading {} frames", m_passes, m_shape.frames), m_shape.height);
}

void ShotStream::read_band(Band& band, int row_begin, int row_end, Cleaning cleaning, bool with_pass_through)
{
    throw_if_cancelled();
    band.row_begin = row_begin;
    band.row_end = row_end;
    band.rows = row_samples() * (row_end - row_begin);
    band.stride = band.rows;
    band.storage.resize(static_cast<size_t>(band.rows) * m_shape.frames);
    band.data = band.storage.data();
    if (with_pass_through)
        band.pass_through.resize(static_cast<size_t>(m_shape.frames));
    else
        band.pass_through.clear();
    tbb::parallel_for(0, m_shape.frames, [&](int frame) {
        m_source.read_rows(frame, row_begin, row_end, band.data + frame * band.rows,
                           with_pass_through ? &band.pass_through[static_cast<size_t>(frame)] : nullptr);
    });
    const PatchRows patch_rows = m_patches;
    std::vector<float> as_read; // --stage modes: the patch rows as the files hold them
    const std::int64_t patch_first = (patch_rows.row_begin - row_begin) * row_samples();
    const std::int64_t patch_samples = (patch_rows.row_end - patch_rows.row_begin) * row_samples();
    if (patch_rows.patches) {
        as_read.resize(static_cast<size_t>(patch_samples) * m_shape.frames);
        for (int t = 0; t < m_shape.frames; ++t)
            std::copy_n(band.data + t * band.rows + patch_first, patch_samples,
                        as_read.begin() + t * patch_samples);
    }
    const std::int64_t first_sample = static_cast<std::int64_t>(row_begin) * row_samples();
    band.reusable = false;
    if (cleaning == Cleaning::Again) {
        clean_again(band.view(m_shape.frames), first_sample);
    } else {
        measure_roughness(band, Roughness::AsRead);
        std::uint8_t* marks =
            m_plan.in_memory || m_cleaned_samples.empty() ? nullptr : m_cleaned_samples.data() + first_sample;
        const lowrank::OutlierCounts found =
            lowrank::clean_outliers(band.view(m_shape.frames), m_outlier_options, marks, row_layout());
        m_outliers.non_finite += found.non_finite;
        m_outliers.fireflies += found.fireflies;
        measure_roughness(band, Roughness::Cleaned);
    }
    if (patch_rows.patches) { // bitwise, so that a replaced NaN counts too
        const std::int64_t first = (patch_rows.row_begin - patch_rows.first_row) * row_samples();
        for (int t = 0; t < m_shape.frames; ++t)
            for (std::int64_t i = 0; i < patch_samples; ++i) {
                const float cleaned = band.data[t * band.rows + patch_first + i];
                if (std::memcmp(&cleaned, &as_read[static_cast<size_t>(t * patch_samples + i)],
                                sizeof cleaned))
                    patch_rows.patches->push_back({t, first + i, cleaned});
            }
    }
}

void ShotStream::clean_again(const lowrank::MutableBandView& rows, std::int64_t first_sample)
{
    if (m_cleaned_samples.empty()) // no counted read marked them: clean in full
        lowrank::clean_outliers(rows, m_outlier_options, nullptr, row_layout());
    else
        lowrank::clean_marked_outliers(rows, m_outlier_options, m_cleaned_samples.data() + first_sample,
                                       row_layout());
}

bool ShotStream::roll_band(Band& band, int row_begin, int row_end, bool with_pass_through)
{
    const int frames = m_shape.frames;
    // Only forward, overlapping, with the same kind of rows, and not while a farm task records patches.
    if (!band.reusable || m_patches.patches || row_begin < band.row_begin || row_begin >= band.row_end ||
        row_end < band.row_end ||
        with_pass_through != (band.pass_through.size() == static_cast<size_t>(frames)))
        return false;
    const std::int64_t samples = row_samples();
    const std::int64_t old_rows = band.rows, new_rows = samples * (row_end - row_begin);
    const std::int64_t shift = samples * (row_begin - band.row_begin),
                       kept = samples * (band.row_end - row_begin);
    // Frame t moves down, from t·old_rows + shift to t·new_rows, frames in
    // order. A band that grows (the first ones, whose halo the image's top
    // clips) is read afresh.
    if (new_rows > old_rows)
        return false;
    float* data = band.storage.data();
    for (std::int64_t t = 0; t < frames; ++t)
        std::memmove(data + t * new_rows, data + t * old_rows + shift,
                     static_cast<size_t>(kept) * sizeof(float));
    const int new_first = band.row_end;
    band.row_begin = row_begin;
    band.row_end = row_end;
    band.rows = band.stride = new_rows;
    band.data = data;
    tbb::parallel_for(0, frames, [&](int frame) {
        PassThroughRows added;
        if (new_first < row_end)
            m_source.read_rows(frame, new_first, row_end, data + frame * new_rows + kept,
                               with_pass_through ? &added : nullptr);
        if (!with_pass_through)
            return;
        // The other channels' rows: the shared ones kept, the new ones after them.
        PassThroughRows& rows = band.pass_through[static_cast<size_t>(frame)];
        if (rows.bytes.empty() || (new_first < row_end && added.bytes.empty()) || rows.row_end != new_first) {
            rows = {};
            return;
        }
        const size_t row_bytes = rows.bytes.size() / static_cast<size_t>(rows.row_end - rows.row_begin);
        rows.bytes.erase(rows.bytes.begin(),
                         rows.bytes.begin() +
                             static_cast<std::ptrdiff_t>(row_bytes * (row_begin - rows.row_begin)));
        rows.bytes.insert(rows.bytes.end(), added.bytes.begin(), added.bytes.end());
        rows.row_begin = row_begin;
        rows.row_end = row_end;
    });
    if (new_first < row_end)
        clean_again({data + kept, new_rows - kept, frames, new_rows},
                    static_cast<std::int64_t>(new_first) * samples);
    return true;
}

void ShotStream::measure_roughness(const Band& band, Roughness which)
{
    std::vector<double>& rows = which == Roughness::AsRead ? m_row_roughness : m_row_cleaned_roughness;
    if (rows.empty())
        rows.assign(static_cast<size_t>(m_shape.height) * m_shape.frames, 0.0);
    row_roughness(band.view(m_shape.frames).view(), m_shape.width, m_shape.channels,
                  band.row_end - band.row_begin,
                  rows.data() + static_cast<std::int64_t>(band.row_begin) * m_shape.frames,
                  which == Roughness::AsRead ? RowMeasure::Absolute : RowMeasure::Squared);
}

std::vector<double> ShotStream::roughness_blocks(int row_begin, int row_end, Roughness which) const
{
    const std::vector<double>& rows = which == Roughness::AsRead ? m_row_roughness : m_row_cleaned_roughness;
    if (rows.empty())
        throw internal_error("roughness_blocks: no first read yet");
    return denoise::roughness_blocks(rows.data() + static_cast<std::int64_t>(row_begin) * m_shape.frames,
                                     m_shape.frames, row_begin, row_end);
}

std::vector<double> ShotStream::frame_noise_factors() const
{
    return denoise::frame_noise_factors(roughness_blocks(0, m_shape.height), m_shape.frames);
}

std::vector<double> ShotStream::frame_scale_factors() const
{
    return denoise::frame_scale_factors(roughness_blocks(0, m_shape.height, Roughness::Cleaned),
                                        m_shape.frames);
}

void ShotStream::ensure_whole_shot()
{
    if (!m_plan.in_memory || m_whole.data)
        return;
    ++m_passes;
    m_progress.begin(fmt::format("reading {} frames", m_shape.frames), m_shape.height);
    read_band(m_whole, 0, m_shape.height, Cleaning::Again);
    m_progress.end();
}

void ShotStream::read_whole_frames(int frame_begin, int frame_end)
{
    if (!m_plan.in_memory || m_passes > 0 || m_whole_read_ahead)
        throw internal_error("read_whole_frames: only a kept shot, before its first pass");
    throw_if_cancelled();
    if (!m_whole.data) {
        m_whole.row_begin = 0;
        m_whole.row_end = m_shape.height;
        m_whole.rows = m_whole.stride = row_samples() * m_shape.height;
        m_whole.storage.resize(static_cast<size_t>(m_whole.rows) * m_shape.frames);
        m_whole.data = m_whole.storage.data();
    }
    tbb::parallel_for(frame_begin, frame_end, [&](int frame) {
        m_source.read_rows(frame, 0, m_shape.height, m_whole.data + frame * m_whole.rows, nullptr);
    });
}

void ShotStream::finish_whole_shot()
{
    measure_roughness(m_whole, Roughness::AsRead);
    const lowrank::OutlierCounts found =
        lowrank::clean_outliers(m_whole.view(m_shape.frames), m_outlier_options, nullptr, row_layout());
    m_outliers.non_finite += found.non_finite;
    m_outliers.fireflies += found.fireflies;
    measure_roughness(m_whole, Roughness::Cleaned);
    m_whole_read_ahead = true;
}

Band& ShotStream::band_with_halo(Band& band, int row, int end, bool with_pass_through, bool keeps_rows)
{
    const int begin = std::max(0, row - m_plan.halo_rows),
              stop = std::min(m_shape.height, end + m_plan.halo_rows);
    if (!m_plan.in_memory) {
        throw_if_cancelled();
        if (!keeps_rows || !m_plan.rolls || !roll_band(band, begin, stop, with_pass_through))
            read_band(band, begin, stop, Cleaning::Again, with_pass_through);
        band.reusable = keeps_rows;
        return band;
    }
    band.row_begin = begin;
    band.row_end = stop;
    band.rows = row_samples() * (stop - begin);
    band.stride = m_whole.stride;
    band.data = m_whole.data + row_samples() * begin;
    return band;
}

void ShotStream::read_raw_frame_rows(int frame, int row_begin, int row_end, const Band& cleaned,
                                     ScratchBuffer<float>& raw)
{
    throw_if_cancelled();
    const std::int64_t rows = row_samples() * (row_end - row_begin);
    const std::int64_t first = (row_begin - cleaned.row_begin) * row_samples();
    raw.resize(static_cast<size_t>(rows)); // read_rows writes every value
    float* destination = raw.data();
    m_source.read_rows(frame, row_begin, row_end, destination, nullptr);
    const float* clean = cleaned.data + frame * cleaned.stride + first;
    for (std::int64_t i = 0; i < rows; ++i)
        if (!std::isfinite(destination[i]))
            destination[i] = clean[i];
}

Band& ShotStream::read_task_band(Band& band, int row, int end)
{
    read_band(band, std::max(0, row - m_plan.halo_rows), std::min(m_shape.height, end + m_plan.halo_rows),
              Cleaning::Again);
    return band;
}

} // namespace modestack::denoise
