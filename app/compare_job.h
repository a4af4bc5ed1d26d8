// `modestack compare` as a library call: the CompareJob (the two sequences,
// layers, frames, thresholds and the --json path, checked as an output before
// any work), compare() that reads both sequences frame by frame and returns
// every figure in a CompareResult, and compare_json() that writes it. Unless
// quiet, compare() streams idiff's table to stdout as the frames are read.
#pragma once

#include "app/run_context.h"
#include "core/common/error.h"
#include "core/metrics/sequence_comparison.h"
#include "io/exr_codec.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace modestack::app {

/// A comparison as typed; CLI11 has checked each threshold's range.
struct CompareJob {
    std::string test;       ///< sequence under test (A)
    std::string reference;  ///< reference sequence (B)
    std::vector<std::string> layers;
    std::string frames;
    metrics::PixelThresholds thresholds;
    metrics::VerdictRule rule;
    std::string json_path;  ///< checked before any work: not one of the inputs
    io::ExrCodec exr_codec = io::ExrCodec::Libdeflate;  ///< --exr-codec
};

/// One compared frame.
struct ComparedFrame {
    int frame = 0;
    metrics::FrameComparison comparison;
};

/// Every figure of a comparison: what the --json summary holds.
struct CompareResult {
    std::string test, reference;  ///< the patterns as given
    std::vector<int> frames;
    int width = 0, height = 0;
    std::vector<std::string> test_channels, reference_channels;
    metrics::PixelThresholds thresholds;
    metrics::VerdictRule rule;
    std::vector<ComparedFrame> per_frame;
    metrics::ErrorSums shot;
    int frames_failing = 0, frames_warning = 0;
    metrics::Verdict verdict = metrics::Verdict::Pass;
};

/// The sequences differ in size or channels (idiff's ErrDifferentSize).
class LayoutMismatch : public Error {
public:
    LayoutMismatch(const std::string& reason, const std::string& file) : Error(ErrorKind::BadInput, reason, file) {}
};

/// Compares the sequences of `job`.
CompareResult compare(const CompareJob& job, const CommonOptions& context);

/// The --json summary of a comparison.
nlohmann::ordered_json compare_json(const CompareResult& result);

}  // namespace modestack::app
