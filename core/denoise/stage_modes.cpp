#include "core/denoise/stage_modes.h"

#include "core/common/error.h"

#include <algorithm>

namespace modestack::denoise {
namespace {

// Copies `modes` images of `band_size` values each from a band into whole-image
// images of `image_size` values, at `first`.
void place_images(const std::vector<float>& band, int modes, std::int64_t band_size, std::vector<float>& image,
                  std::int64_t image_size, std::int64_t first)
{
    for (int j = 0; j < modes; ++j)
        std::copy_n(band.begin() + j * band_size, band_size, image.begin() + j * image_size + first);
}

}  // namespace

ShotModes join_modes_bands(const std::vector<ModeImages>& bands, const ShotShape& shape, int residual_modes,
                           int output_modes, int gain_modes)
{
    const std::int64_t row_samples = static_cast<std::int64_t>(shape.width) * shape.channels;
    const std::int64_t samples = row_samples * shape.height, pixels = samples / shape.channels;
    ShotModes shot;
    shot.residual_modes = residual_modes;
    shot.output_modes = output_modes;
    shot.gain_modes = gain_modes;
    shot.residual.resize(static_cast<size_t>(samples) * residual_modes);
    shot.output.resize(static_cast<size_t>(samples) * output_modes);
    shot.noise_variance.resize(static_cast<size_t>(samples));
    shot.gains.resize(static_cast<size_t>(pixels) * gain_modes);
    shot.patches.resize(static_cast<size_t>(shape.frames));
    int covered = 0;
    for (const ModeImages& band : bands) {
        const std::int64_t band_samples = row_samples * (band.row_end - band.row_begin);
        const std::int64_t band_pixels = band_samples / shape.channels;
        if (band.row_begin != covered || band.row_end <= band.row_begin || band.row_end > shape.height ||
            band.residual_modes != residual_modes || band.output_modes != output_modes ||
            band.gain_modes != gain_modes ||
            band.residual.size() != static_cast<size_t>(band_samples * residual_modes) ||
            band.output.size() != static_cast<size_t>(band_samples * output_modes) ||
            band.noise_variance.size() != static_cast<size_t>(band_samples) ||
            band.gains.size() != static_cast<size_t>(band_pixels * gain_modes) ||
            band.bias.size() != static_cast<size_t>(band.row_end - band.row_begin))
            throw internal_error("the modes bands do not fit the shot and its solve");
        const std::int64_t first = row_samples * band.row_begin;
        place_images(band.residual, residual_modes, band_samples, shot.residual, samples, first);
        place_images(band.output, output_modes, band_samples, shot.output, samples, first);
        place_images(band.noise_variance, 1, band_samples, shot.noise_variance, samples, first);
        place_images(band.gains, gain_modes, band_pixels, shot.gains, pixels, first / shape.channels);
        shot.bias.insert(shot.bias.end(), band.bias.begin(), band.bias.end());
        for (const ModeImages::Patch& patch : band.patches) {
            if (patch.frame < 0 || patch.frame >= shape.frames || patch.sample < 0 || patch.sample >= band_samples)
                throw internal_error("a modes band's patch lies outside it");
            shot.patches[static_cast<size_t>(patch.frame)].push_back({patch.frame, first + patch.sample, patch.value});
        }
        covered = band.row_end;
    }
    if (covered != shape.height)
        throw internal_error("the modes bands do not cover the shot");
    return shot;
}

}  // namespace modestack::denoise
