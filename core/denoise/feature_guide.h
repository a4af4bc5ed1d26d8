// The albedo, normal and depth channels of the input as a guide for the mode
// filter (mode_filter.h; [0052], [0058]; docs/design.md, "Estimators": on sharp
// shadows and texture edges the blur must be edge-aware to gain). These features come from the first
// surface a camera ray hits, not from the indirect light's random paths, so their
// noise is independent of the coefficient images' noise: weights built from them
// are fixed with respect to that noise and SURE stays unbiased, for every mode
// including the first (which c_1's own guide cannot filter).
//
// Each feature is averaged over a few frames spread over the shot (the image-space
// method assumes a static camera, so they show the same surfaces; averaging only
// removes pixel-filter jitter at edges) and divided by its own scale, measured
// from the data: the root mean square of its differences between neighbouring
// pixels over the whole image. That is dominated by the image's edges, so a
// difference well below it is the smooth variation inside a surface and one near
// or above it is an edge; the filter's range widths are multiples of it, and SURE
// picks the multiple (or no feature guide at all). Depth is guided by its
// logarithm, so that its scale is relative. A feature that is the same everywhere
// carries no edge and is dropped.
#pragma once

#include "core/common/progress.h"
#include "core/denoise/frame_stream.h"

#include <string>
#include <vector>

namespace modestack::denoise {

/// Which features guide the mode filter, and from how many frames.
struct FeatureGuideOptions {
    std::vector<Auxiliary> kinds{Auxiliary::Albedo, Auxiliary::Normal, Auxiliary::Depth};
    /// Frames averaged (spread evenly over the shot, first and last included).
    int frames = 4;
};

/// What the guide uses, for the JSON summary and the report.
struct FeatureGuideSummary {
    std::vector<std::string> features;  ///< "albedo", "normal", "depth" (those present and not constant)
    std::vector<double> scales;         ///< each one's RMS neighbour difference (depth: of its logarithm)
    std::vector<int> frames;            ///< frame indices averaged
};

/// "albedo", "normal", "depth" or "variance".
std::string auxiliary_name(Auxiliary kind);

/// The features of a shot, normalised, row by row.
class FeatureGuide {
public:
    /// Finds which of options.kinds the source has and measures their scales
    /// (one read of those features of the chosen frames, in bands).
    FeatureGuide(FrameSource& source, const FeatureGuideOptions& options, Progress& progress);

    /// Feature channels per pixel (0: the input has no usable feature).
    int channels() const { return m_channels; }
    const FeatureGuideSummary& summary() const { return m_summary; }

    /// Rows [row_begin, row_end) of the normalised features, [row][x][channel],
    /// averaged over the chosen frames.
    void read_rows(int row_begin, int row_end, std::vector<float>& features) const;

private:
    struct Feature {
        Auxiliary kind;
        int channels = 0;
        double scale = 1;
    };
    // Rows of one feature averaged over the chosen frames (depth as a logarithm), unscaled.
    void read_feature(const Feature& feature, int row_begin, int row_end, std::vector<float>& values) const;

    FrameSource& m_source;
    ShotShape m_shape;
    std::vector<int> m_frames;
    std::vector<Feature> m_features;
    int m_channels = 0;
    FeatureGuideSummary m_summary;
};

}  // namespace modestack::denoise
