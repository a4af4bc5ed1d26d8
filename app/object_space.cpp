// The wiring of object-space denoising (see object_space.h).
#include "app/object_space.h"

#include "app/memory_budget.h"
#include "app/sequence_adapters.h"
#include "core/common/error.h"
#include "core/objectspace/point_denoise.h"
#include "core/objectspace/point_rebuild.h"
#include "io/frame_header.h"
#include "io/sequence_reader.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <utility>

namespace modestack::app {
namespace {

using objectspace::kLookupChannels;

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
    if (const std::optional<std::string> value = io::find_attribute(header, "modestack:points")) {
        const std::optional<std::int64_t> count = io::attribute_count(*value, slots);
        if (!count)
            throw bad_input(header.file, fmt::format("modestack:points is {}: not a point count of a {}x{} "
                                                     "point image",
                                                     *value, points.width(), points.height()));
        result.count = *count;
    }
    if (const std::optional<std::string> value = io::find_attribute(header, "modestack:point_spacing")) {
        const std::optional<double> spacing = io::attribute_number(*value);
        if (!spacing || *spacing < 0)
            throw bad_input(header.file, fmt::format("modestack:point_spacing is {}: not a spacing", *value));
        result.spacing = *spacing;
    }
    return result;
}

// Positions and normals of the points in the shot's first frame (their rest
// pose: neighbours on a surface stay neighbours as it moves), or an empty
// result when the points files lack either layer.
objectspace::SurfaceSamples read_surface_samples(const io::FrameSequence& files, std::int64_t count,
                                                 double spacing, io::ExrCodec codec)
{
    objectspace::SurfaceSamples samples;
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

// What one frame rebuilt from the points holds at once: its lookup, layer and
// sigma as floats, its point image's values and sigma, and its other channels,
// which the output carries over (read whole, then encoded).
std::int64_t output_frame_bytes(const io::SequenceReader& frames, const io::SequenceReader& points)
{
    const std::int64_t pixels = static_cast<std::int64_t>(frames.width()) * frames.height();
    const std::int64_t all_channels = static_cast<std::int64_t>(frames.channel_names(0).size());
    const std::int64_t channels = frames.selected_channel_count();
    const std::int64_t point_values = static_cast<std::int64_t>(points.width()) * points.height() * channels;
    return static_cast<std::int64_t>(sizeof(float)) *
           (pixels * (kLookupChannels + 2 * channels + 2 * all_channels) + 3 * point_values);
}

} // namespace

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

    if (!job.conventions)
        throw internal_error("the object-space job has no renderer conventions");
    const RendererChoice renderer =
        choose_renderer(*job.conventions, job.renderer, io::read_frame_header(point_files.files.front()));
    SequenceSource point_source(point_reader, auxiliary_candidates(renderer, point_reader.layers()));
    objectspace::SurfaceFilterOptions filter;
    filter.widths = job.filter_widths;
    filter.filter = job.surface_filter;
    filter.window_spacings = std::max(1, job.sigma_radius);
    const objectspace::SurfaceSamples samples =
        read_surface_samples(point_files, result.points, header.spacing, job.exr_codec);
    SequenceSink sink(frame_reader, job.outputs, "");
    sink.set_part_layout(job.part_layout);
    sink.set_output_format(job.output_format);
    // The budget is the whole process's, as for images: less what it holds
    // already, the points files' decoders, the outputs' buffers and what each
    // frame rebuilt at once holds after the engine (output_frame_bytes).
    const int frames_at_once = tbb::this_task_arena::max_concurrency();
    settings.max_memory_bytes =
        engine_memory_budget(settings.max_memory_bytes, point_reader, sink.open_output_bytes()) -
        frames_at_once * output_frame_bytes(frame_reader, point_reader);
    if (settings.max_memory_bytes <= 0)
        throw usage_error(
            fmt::format("--max-memory is too small for object space: rebuilding {} frames at once "
                        "alone takes more",
                        frames_at_once));
    objectspace::PointDenoise denoised =
        objectspace::denoise_points(point_source, settings, samples, filter, progress);
    result.report = std::move(denoised.report);
    result.filter = std::move(denoised.filter);
    result.points_read_again = denoised.over_surfaces && !denoised.input_kept;
    if (!denoised.over_surfaces)
        progress.warn(fmt::format("{} has no Position and Normal layers or no modestack:point_spacing: sigma is "
                                  "the point image's and the points are not filtered over the surfaces",
                                  point_files.files.front()));

    std::vector<io::HeaderAttribute> attributes = job.attributes;
    attributes.push_back(io::HeaderAttribute::of_text("modestack:object_space", point_files.printf_pattern));
    attributes.push_back(io::HeaderAttribute::of_integer("modestack:points", result.points));
    sink.set_attributes(std::move(attributes));
    sink.begin(
        {result.report.rank_decision.kept_modes, result.report.rank_decision.rule, result.report.solver, {}});
    const int frames = frame_reader.frame_count(), channels = frame_reader.selected_channel_count();
    const std::size_t pixels = static_cast<std::size_t>(frame_reader.width()) * frame_reader.height();
    progress.begin(fmt::format("rebuilding {} frames from {} points", frames, result.points), frames);
    tbb::parallel_for(0, frames, [&](int frame) {
        if (job.outputs[static_cast<std::size_t>(frame)].empty()) {
            progress.advance(1);
            return;
        }
        std::vector<float> lookup(pixels * kLookupChannels), rebuilt(pixels * channels), sigma(pixels * channels);
        std::vector<float> point_values(static_cast<std::size_t>(denoised.frame_values())),
            point_sigma(point_values.size());
        denoised.frame(frame, point_values.data(), point_sigma.data());
        lookup_reader->read_selected(frame, 0, frame_reader.height(), lookup.data());
        objectspace::rebuild_from_points(
            lookup.data(), pixels, point_values.data(), point_sigma.data(), channels, result.points,
            job.frames.files[static_cast<std::size_t>(frame)], rebuilt.data(), sigma.data());
        sink.write_rows(frame, 0, frame_reader.height(), rebuilt.data(), sigma.data(), nullptr);
        progress.advance(1);
    });
    progress.end();
    sink.commit();
    return result;
}

} // namespace modestack::app
