// Object-space denoising (see object_space.h).
#include "app/object_space.h"

#include "app/sequence_adapters.h"
#include "core/common/error.h"
#include "core/render/aov.h"
#include "io/frame_header.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>

namespace modestack::app {
namespace {

constexpr int kLookupChannels = 2 * render::kLookupPoints;

// What `render --points` recorded in the header of a points sequence.
struct PointHeader {
    std::int64_t count = 0; ///< points; every slot of the point image when not recorded
    double spacing = 0;     ///< lattice spacing in metres; 0 when not recorded
};

PointHeader read_point_header(const io::SequenceReader& points)
{
    const io::FrameHeader header = io::read_frame_header(points.sequence().files.front());
    const std::int64_t slots = static_cast<std::int64_t>(points.width()) * points.height();
    PointHeader result{slots, 0.0};
    // Attribute values read "type value": the number is the last word.
    auto number = [](const std::string& value) { return value.substr(value.find_last_of(' ') + 1); };
    for (const auto& [name, value] : header.attributes) {
        if (name == "modestack:points") {
            result.count = std::atoll(number(value).c_str());
            if (result.count < 1 || result.count > slots)
                throw bad_input(header.file, fmt::format("records {} points in a {}x{} point image", result.count,
                                                         points.width(), points.height()));
        } else if (name == "modestack:point_spacing") {
            result.spacing = std::atof(number(value).c_str());
        }
    }
    return result;
}

// Keeps a copy of every row the engine reads: the noisy points sigma needs after
// the rebuild, without decoding the points files a second time.
class KeepingSource : public denoise::ForwardingSource {
public:
    explicit KeepingSource(denoise::FrameSource& inner) : ForwardingSource(inner), m_shape(inner.shape())
    {
        m_rows.assign(static_cast<std::size_t>(m_shape.frames), std::vector<float>(row_values() * m_shape.height));
    }
    void read_rows(int frame_index, int row_begin, int row_end, float* destination) override
    {
        m_inner.read_rows(frame_index, row_begin, row_end, destination);
        std::copy(destination, destination + row_values() * (row_end - row_begin),
                  m_rows[static_cast<std::size_t>(frame_index)].begin() + row_values() * row_begin);
    }
    const float* frame(int frame_index) const { return m_rows[static_cast<std::size_t>(frame_index)].data(); }

private:
    std::size_t row_values() const { return static_cast<std::size_t>(m_shape.width) * m_shape.channels; }
    denoise::ShotShape m_shape;
    std::vector<std::vector<float>> m_rows; // per frame, [row][x][channel]
};

// Positions and normals of the points in the shot's first frame (their rest
// pose: neighbours on a surface stay neighbours as it moves), or an empty
// result when the points files lack either layer.
denoise::SurfaceSamples read_surface_samples(const io::FrameSequence& files, std::int64_t count, double spacing,
                                             io::ExrCodec codec)
{
    denoise::SurfaceSamples samples;
    samples.spacing = spacing;
    io::FrameSequence first = files;
    first.files.resize(1);
    first.frames.resize(1);
    auto read_layer = [&](const char* layer, std::vector<float>& out) {
        try {
            io::SequenceReader reader(first, {layer}, codec);
            if (reader.selected_channel_count() != 3)
                return false;
            std::vector<float> all(static_cast<std::size_t>(reader.width()) * reader.height() * 3);
            reader.read_selected(0, 0, reader.height(), all.data());
            out.assign(all.begin(), all.begin() + count * 3);
            return true;
        } catch (const Error&) {
            return false;
        }
    };
    if (!read_layer("Position", samples.positions) || !read_layer("Normal", samples.normals))
        return {};
    return samples;
}

std::unique_ptr<io::SequenceReader> open_lookup(const io::FrameSequence& frames, io::ExrCodec codec)
{
    std::unique_ptr<io::SequenceReader> lookup;
    try {
        lookup = std::make_unique<io::SequenceReader>(frames, std::vector<std::string>{"PointLookup"}, codec);
    } catch (const Error&) {
        throw bad_input(frames.files.front(), "has no PointLookup layer: render the shot with render --points "
                                              "for --object-space");
    }
    if (lookup->selected_channel_count() != kLookupChannels)
        throw bad_input(frames.files.front(), fmt::format("PointLookup has {} channels, not {} (I0-I3, W0-W3)",
                                                          lookup->selected_channel_count(), kLookupChannels));
    return lookup;
}

} // namespace

PointStore::PointStore(denoise::ShotShape shape) : m_shape(shape)
{
    const std::size_t values = static_cast<std::size_t>(shape.width) * shape.height * shape.channels;
    m_values.assign(static_cast<std::size_t>(shape.frames), std::vector<float>(values, 0.0f));
    m_sigma = m_values;
}

void PointStore::write_rows(int frame_index, int row_begin, int row_end, const float* rebuilt, const float* sigma)
{
    const std::size_t row_values = static_cast<std::size_t>(m_shape.width) * m_shape.channels;
    const std::size_t first = static_cast<std::size_t>(row_begin) * row_values;
    const std::size_t count = static_cast<std::size_t>(row_end - row_begin) * row_values;
    std::copy(rebuilt, rebuilt + count, m_values[static_cast<std::size_t>(frame_index)].begin() + first);
    std::copy(sigma, sigma + count, m_sigma[static_cast<std::size_t>(frame_index)].begin() + first);
}

void rebuild_from_points(const float* lookup, std::size_t pixels, const float* point_values,
                         const float* point_sigma, int channels, std::int64_t point_count, const std::string& file,
                         float* rebuilt, float* sigma)
{
    const std::size_t ch = static_cast<std::size_t>(channels);
    for (std::size_t p = 0; p < pixels; ++p) {
        const float* entry = lookup + p * kLookupChannels;
        double value[4] = {0, 0, 0, 0}, error[4] = {0, 0, 0, 0};
        std::fill(rebuilt + p * ch, rebuilt + (p + 1) * ch, 0.0f);
        std::fill(sigma + p * ch, sigma + (p + 1) * ch, 0.0f);
        for (int k = 0; k < render::kLookupPoints; ++k) {
            const float weight = entry[render::kLookupPoints + k];
            if (!(weight > 0))
                continue;
            const float id = entry[k];
            if (!(id >= 0 && id < static_cast<float>(point_count)))
                throw bad_input(file, fmt::format("PointLookup names point {} of pixel {}, but the points sequence "
                                                  "has {} points",
                                                  id, p, point_count));
            const std::size_t point = static_cast<std::size_t>(id);
            for (std::size_t c = 0; c < ch && c < 4; ++c) {
                value[c] += static_cast<double>(weight) * point_values[point * ch + c];
                error[c] += static_cast<double>(weight) * point_sigma[point * ch + c];
            }
        }
        for (std::size_t c = 0; c < ch && c < 4; ++c) {
            rebuilt[p * ch + c] = static_cast<float>(value[c]);
            sigma[p * ch + c] = static_cast<float>(error[c]);
        }
    }
}

ObjectSpaceResult run_object_space(const ObjectSpaceJob& job, denoise::Settings settings, Progress& progress)
{
    io::SequenceReader frame_reader(job.frames, job.layers, job.exr_codec);
    std::unique_ptr<io::SequenceReader> lookup_reader = open_lookup(job.frames, job.exr_codec);
    io::FrameSequence point_files = io::find_input_sequence(job.points, io::describe_frames(job.frames.frames));
    io::SequenceReader point_reader(point_files, job.layers, job.exr_codec);
    if (point_reader.selected_channel_count() != frame_reader.selected_channel_count() ||
        point_reader.selected_channel_count() > 4)
        throw bad_input(point_files.files.front(),
                        fmt::format("has {} channels in the selected layers, the frames {}: --layer must name the "
                                    "same layer (at most 4 channels) in both",
                                    point_reader.selected_channel_count(), frame_reader.selected_channel_count()));
    ObjectSpaceResult result;
    const PointHeader header = read_point_header(point_reader);
    result.points = header.count;
    result.frame_width = frame_reader.width();
    result.frame_height = frame_reader.height();

    // Neighbours in a point image are not neighbours on the surfaces: nothing spatial.
    settings.mode_filter.enabled = false;
    settings.feature_guide.kinds.clear();
    settings.rank_map.enabled = false;
    settings.sigma_radius = 0;
    SequenceSource point_source(point_reader);
    KeepingSource noisy(point_source);  // every row is read: pass 1 needs them all for the statistics
    PointStore store(point_source.shape());
    result.report = denoise::run_denoise(noisy, store, settings, progress);
    // Sigma (and the filter) over the surfaces: the engine's sigma pooled over a
    // point image's rows, which are not surface neighbours.
    denoise::SurfaceSamples samples = read_surface_samples(point_files, result.points, header.spacing, job.exr_codec);
    if (samples.count() == 0 || !(samples.spacing > 0)) {
        progress.warn(fmt::format("{} has no Position and Normal layers or no modestack:point_spacing: sigma is "
                                  "the point image's and the points are not filtered over the surfaces",
                                  point_files.files.front()));
    } else {
        const int frame_count = point_reader.frame_count();
        std::vector<denoise::SurfaceFrame> frames;
        for (int t = 0; t < frame_count; ++t) {
            double leverage = 0;
            for (const std::vector<double>& mode : result.report.temporal_modes)
                leverage += mode[static_cast<std::size_t>(t)] * mode[static_cast<std::size_t>(t)];
            frames.push_back({noisy.frame(t), store.values(t), store.sigma(t), leverage});
        }
        denoise::SurfaceFilterOptions options;
        options.widths = job.filter_widths;
        options.filter = job.surface_filter;
        options.window_spacings = std::max(1, job.sigma_radius);
        options.rank = result.report.rank.rank;
        progress.begin("surface filter and sigma", 1);
        result.filter = denoise::filter_surfaces(samples, options, point_reader.selected_channel_count(), frames);
        progress.end();
    }

    SequenceSink sink(frame_reader, job.outputs, "");
    std::vector<io::HeaderAttribute> attributes = job.attributes;
    attributes.push_back(io::HeaderAttribute::of_text("modestack:object_space", point_files.printf_pattern));
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:points", result.points));
    sink.set_attributes(std::move(attributes));
    sink.begin({result.report.rank.rank, result.report.rank.rule, result.report.solver});
    const int frames = frame_reader.frame_count(), channels = frame_reader.selected_channel_count();
    const std::size_t pixels = static_cast<std::size_t>(frame_reader.width()) * frame_reader.height();
    progress.begin(fmt::format("rebuilding {} frames from {} points", frames, result.points), frames);
    tbb::parallel_for(0, frames, [&](int frame) {
        if (job.outputs[static_cast<std::size_t>(frame)].empty()) {
            progress.advance(1);
            return;
        }
        std::vector<float> lookup(pixels * kLookupChannels), rebuilt(pixels * channels), sigma(pixels * channels);
        lookup_reader->read_selected(frame, 0, frame_reader.height(), lookup.data());
        rebuild_from_points(lookup.data(), pixels, store.values(frame), store.sigma(frame), channels,
                            result.points, job.frames.files[static_cast<std::size_t>(frame)], rebuilt.data(),
                            sigma.data());
        sink.write_rows(frame, 0, frame_reader.height(), rebuilt.data(), sigma.data());
        progress.advance(1);
    });
    progress.end();
    sink.commit();
    return result;
}

} // namespace modestack::app
