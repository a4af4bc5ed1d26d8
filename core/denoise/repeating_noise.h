// Noise that repeats from frame to frame (docs/design.md, "Noise that repeats"):
// a renderer that draws the same random numbers in every frame (a fixed seed,
// Cycles' default, a locked sampling pattern) gives each frame the same noise
// where the picture holds still. That noise lies in the shot's own temporal
// directions, so the rebuild keeps it whole and sigma's noise level, measured
// from what the rebuild removes, does not see it. A spatial estimator can
// remove it, once the choice's risk counts it.
//
// The measurement compares two powers of the input as read, each the square
// of one difference of two values, so that under noise new in every pixel and
// frame both have the same distribution, whatever its shape (sparse 4-spp
// noise included):
//   temporal: (y_{t+1}(x) − y_t(x))² / 2 over a few pairs of consecutive frames,
//   spatial:  (y_t(x) − y_t(x + 1))² / 2 in the first frame of each pair,
//   coarse:   the same with the neighbour 2 pixels along,
// y the channel mean of the pixel; per pixel the median over the pairs, then
// the median over pixels (robust to fireflies, edges and a pair that straddles
// a change of the lighting). Noise new in every frame gives temporal ≈ spatial
// (the picture's detail only adds to spatial); noise that repeats gives
// temporal ≈ 0, so the repeating share is 1 − temporal/spatial. Still detail of
// a clean picture would look the same, but a picture's detail seen through the
// renderer's pixel filter is smooth at the pixel scale, while render noise is
// white: its power 1 pixel apart equals that 2 apart. So the noise is said to
// repeat only where at least half of the pixel-scale variation stays from frame
// to frame *and* it is white (spatial at least half of coarse). Direct light,
// whose pixel-scale variation is mostly its edges, stays below the first bar
// even where its noise repeats (measured: bench/results/estimators.md).
#pragma once

#include "core/common/progress.h"
#include "core/denoise/frame_stream.h"

#include <vector>

namespace modestack::denoise {

/// What the measurement found.
struct RepeatingNoise {
    bool measured = false;   ///< false: not looked for (no estimator choice) or too few frames
    double temporal = 0;     ///< median frame-to-frame power (see the file comment)
    double spatial = 0;      ///< median power between neighbours in a row
    double coarse = 0;       ///< the same 2 pixels apart
    double share = 0;        ///< 1 − temporal/spatial in [0, 1] (0 where spatial is 0)
    double whiteness = 0;    ///< spatial/coarse (0 where coarse is 0)
    bool repeats = false;    ///< share ≥ 0.5 and whiteness ≥ 0.5
    std::vector<int> frames; ///< the frame indices read, in pairs of consecutive frames

    /// The share the estimator choice counts: share where the noise repeats, else 0.
    double counted_share() const { return repeats ? share : 0.0; }
};

/// Pairs of consecutive frames read (fewer in a shot of fewer frames).
inline constexpr int kRepeatingNoisePairs = 3;
/// Rows read at a time: each frame read is read in this many rows per call.
inline constexpr int kRepeatingNoiseBandRows = 64;

/// A run of channels measured together (a layer): `count` channels from `first`.
struct ChannelGroup {
    int first = 0;
    int count = 0;
};

/// Measures `source`'s frames in pairs spread over the shot (first and last
/// pair at the shot's ends), in bands of rows, each group of channels on its
/// own from the one read. Deterministic: the same frames and the same result
/// for a whole run and a farm.
std::vector<RepeatingNoise>
measure_repeating_noise(FrameSource& source, const std::vector<ChannelGroup>& groups, Progress& progress);
/// The same over all of the source's channels together.
RepeatingNoise measure_repeating_noise(FrameSource& source, Progress& progress);

} // namespace modestack::denoise
