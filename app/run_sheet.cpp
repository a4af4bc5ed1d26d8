#include "app/run_sheet.h"

#include "app/run_composite.h"
#include "core/refine/equal_quality.h"
#include "io/contact_sheet.h"
#include "io/sequence_reader.h"

#include <algorithm>
#include <memory>

namespace modestack::app {

std::vector<int> sheet_frame_indices(const std::vector<int>& frames, const scene::FrameSpan& highlight)
{
    std::vector<int> indices;
    int count = static_cast<int>(frames.size());
    for (int k = 0; k < std::min(4, count); ++k)
        indices.push_back(count == 1 ? 0 : k * (count - 1) / std::max(1, std::min(4, count) - 1));
    if (!highlight.empty()) {
        int middle = (highlight.first + highlight.last) / 2;
        auto found = std::find(frames.begin(), frames.end(), middle);
        if (found != frames.end() && indices.size() > 1)
            indices[1] = static_cast<int>(found - frames.begin());
    }
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    return indices;
}

RunMeasurements measure_and_write_sheet(const RunSequences& sequences, const std::vector<int>& frames,
                                        const scene::FrameSpan& highlight, const io::DisplayConverter& display,
                                        const std::string& sheet_path)
{
    io::SequenceReader noisy_passes(sequences.noisy, kPassLayers), noisy_beauty(sequences.noisy, {"Combined"});
    // The denoised beauty from the denoised passes (DiffDir is denoised too), so
    // that it differs from the final one by what refine did alone.
    io::SequenceReader denoised_passes(sequences.denoised, kPassLayers);
    io::SequenceReader final_beauty(sequences.final_frames, {"Combined"}),
        final_indirect(sequences.final_frames, {"DiffInd"});
    std::unique_ptr<io::SequenceReader> reference_beauty, reference_indirect;
    if (sequences.reference) {
        reference_beauty =
            std::make_unique<io::SequenceReader>(*sequences.reference, std::vector<std::string>{"Combined"});
        reference_indirect =
            std::make_unique<io::SequenceReader>(*sequences.reference, std::vector<std::string>{"DiffInd"});
    }
    RunMeasurements measured;
    std::vector<std::vector<std::vector<double>>>& errors = measured.errors;
    errors.assign(2, std::vector<std::vector<double>>(3));
    std::vector<int> sheet = sheet_frame_indices(frames, highlight);
    std::vector<std::vector<float>> sheet_images;
    for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
        bool on_sheet = std::find(sheet.begin(), sheet.end(), i) != sheet.end();
        if (!on_sheet && !reference_beauty)
            continue;
        std::vector<float> passes = read_frame(noisy_passes, i);
        std::vector<float> denoised = read_frame(denoised_passes, i);
        std::vector<float> indirect[3] = {std::vector<float>(passes.size() / 4),
                                          std::vector<float>(passes.size() / 4),
                                          read_frame(final_indirect, i)};
        for (std::size_t p = 0; p < indirect[0].size() / 3; ++p)
            for (int c = 0; c < 3; ++c) {
                indirect[0][p * 3 + c] = passes[p * 12 + 6 + c];
                indirect[1][p * 3 + c] = denoised[p * 12 + 6 + c];
            }
        std::vector<float> beauty[3] = {read_frame(noisy_beauty, i), composite(denoised, nullptr),
                                        read_frame(final_beauty, i)};
        std::vector<float> reference_rgb;
        if (reference_beauty) {
            reference_rgb = read_frame(*reference_beauty, i);
            std::vector<float> reference_indirect_rgb = read_frame(*reference_indirect, i);
            for (int v = 0; v < 3; ++v) {
                errors[0][v].push_back(refine::relative_mse(indirect[v].data(), reference_indirect_rgb.data(),
                                                            indirect[v].size()));
                errors[1][v].push_back(
                    refine::relative_mse(beauty[v].data(), reference_rgb.data(), beauty[v].size()));
            }
        }
        if (on_sheet) {
            for (int v = 0; v < 3; ++v)
                sheet_images.push_back(beauty[v]);
            if (reference_beauty)
                sheet_images.push_back(reference_rgb);
        }
    }
    int columns = reference_beauty ? 4 : 3;
    std::vector<io::ContactSheetCell> cells;
    for (const auto& image : sheet_images)
        cells.push_back({noisy_passes.width(), noisy_passes.height(), image.data()});
    io::write_contact_sheet(sheet_path, columns, cells, display);
    for (int i : sheet)
        measured.shown_frames.push_back(frames[i]);
    return measured;
}

}  // namespace modestack::app
