// Noise that repeats from frame to frame (docs/design.md, "Noise that repeats"):
// a renderer that draws the same random numbers in every frame (a fixed seed,
// Cycles' default, a locked sampling pattern) gives each frame the same noise
// where the picture holds still. That noise lies in the shot's own temporal
// directions, so the rebuild keeps it whole and sigma's noise level, measured
// from what the rebuild removes, does not see it. A spatial estimator can
// remove it, once the choice's risk counts it.
//
// The measurement compares two powers of the input as read, each the square
// of one second difference, so that under noise new in every pixel and frame
// both have the same distribution, whatever its shape (sparse 4-spp noise
// included), and a change that is smooth in time or space (a light that moves,
// a gradient) cancels:
//   temporal: (y_{t−1}(x) − 2·y_t(x) + y_{t+1}(x))² / 6 over a few triples of
//             consecutive frames,
//   spatial:  (y_t(x − 1) − 2·y_t(x) + y_t(x + 1))² / 6 in each triple's middle frame,
//   coarse:   the same with the neighbours 2 pixels away,
// y the channel mean of the pixel; per pixel the median over the triples, then
// the median over pixels (robust to fireflies, edges and a triple that
// straddles a jump of the lighting). Noise new in every frame gives temporal ≈
// spatial (the picture's detail only adds to spatial); noise that repeats gives
// temporal ≈ 0, so the repeating share is 1 − temporal/spatial. Still detail of
// a clean picture would look the same, but a picture's detail seen through the
// renderer's pixel filter is smooth at the pixel scale, while render noise is
// white: its power at 1 pixel equals that at 2. So the noise is said to repeat
// only where at least half of the pixel-scale variation stays from frame to
// frame *and* it is white (spatial at least half of coarse). Measured on the
// benchmark (bench/results/estimators.md): animated seeds 0.19 at most (direct
// light), fixed seeds 0.59 (direct light lit by a light that orbits) and more.
#pragma once

#include "core/common/progress.h"
#include "core/denoise/frame_stream.h"

#include <vector>

namespace modestack::denoise {

/// What the measurement found.
struct RepeatingNoise {
    bool measured = false; ///< false: not looked for (no estimator choice) or too few frames
    double temporal = 0;   ///< median frame-to-frame power (see the file comment)
    double spatial = 0;    ///< median power between neighbours in a row
    double coarse = 0;     ///< the same 2 pixels apart
    double share = 0;      ///< 1 − temporal/spatial in [0, 1] (0 where spatial is 0)
    double whiteness = 0;  ///< spatial/coarse (0 where coarse is 0)
    double level = 0;      ///< √spatial over the median |value|: the pixel-scale variation's relative size
    bool repeats = false;  ///< share ≥ 0.5, whiteness ≥ 0.5 and level ≥ kLeastNoiseLevel
    std::vector<int> frames; ///< the frame indices read, in triples of consecutive frames
    double seconds = 0;      ///< the measurement's wall time (not handed on to a farm's writes)

    /// Whether the estimator choice counts it: where the noise repeats and its
    /// pixel-scale variation is as white as render noise measures (whiteness at
    /// least kCountedWhiteness). The choice takes each pixel's repeating noise
    /// from the input's own high-pass power, which next to a hard shadow's edge
    /// is mostly the edge: counted there it made the blurs take the edges
    /// (bench/results/estimators.md, section 8).
    bool counted() const;
    /// The share the estimator choice counts: share where counted(), else 0.
    double counted_share() const { return counted() ? share : 0.0; }
    /// The share that repeats where the choice's risks do not count it (not
    /// white enough: mostly edges): sigma still counts it, since the rebuild,
    /// the input and the blurs all carry it.
    double uncounted_share() const { return repeats && !counted() ? share : 0.0; }
};

/// The least relative pixel-scale variation that is said to be noise: 0.1 %
/// of the picture's typical value, 7× the rounding of a half float (2^-11/√12
/// RMS), which a clean render repeats in every frame too. A few samples per
/// pixel leave 0.3–5 % at the median pixel of the benchmark's direct light and
/// 30–70 % on its indirect light.
inline constexpr double kLeastNoiseLevel = 0.001;

/// The whiteness from which the choice counts the noise that repeats: white
/// noise measures 1 (0.93–1.01 on the benchmark's indirect light), a picture's
/// edges pull it down (0.73–0.98 on its direct light).
inline constexpr double kCountedWhiteness = 0.9;

/// Triples of consecutive frames read (fewer in a shot of fewer frames).
inline constexpr int kRepeatingNoiseTriples = 3;
/// Rows read at a time: each frame read is read in this many rows per call.
inline constexpr int kRepeatingNoiseBandRows = 64;

/// A run of channels measured together (a layer): `count` channels from `first`.
struct ChannelGroup {
    int first = 0;
    int count = 0;
};

/// Measures `source`'s frames in triples spread over the shot (first and last
/// triple at the shot's ends), in bands of rows, each group of channels on its
/// own from the one read. Deterministic: the same frames and the same result
/// for a whole run and a farm.
std::vector<RepeatingNoise>
measure_repeating_noise(FrameSource& source, const std::vector<ChannelGroup>& groups, Progress& progress);
/// The same over all of the source's channels together.
RepeatingNoise measure_repeating_noise(FrameSource& source, Progress& progress);

} // namespace modestack::denoise
