// idiff's pass/warn/fail rule, applied to the sums of one frame. A frame FAILS
// when more than --fail-percent % of its pixels fail (default 0: any failing
// pixel) or its largest error exceeds --hard-fail; it WARNS likewise with the
// warn figures; otherwise it PASSES. A NaN/Inf mismatch always fails (idiff
// would let it pass under a generous --fail-percent; a CI check should not).
// A shot's verdict is its worst frame's.
#pragma once

#include "core/metrics/image_error.h"

#include <limits>

namespace modestack::metrics {

/// Outcome of a comparison; the values are idiff's exit codes.
enum class Verdict {
    Pass = 0,    ///< every figure within the thresholds
    Warning = 1, ///< over a warn limit, within the fail limits
    Failure = 2, ///< over a fail limit
};

/// The limits of the rule (idiff's defaults).
struct VerdictRule {
    double fail_percent = 0.0;                                  ///< % of pixels allowed to fail
    double warn_percent = 0.0;                                  ///< % of pixels allowed to warn
    double hard_fail = std::numeric_limits<double>::infinity(); ///< fail when any error exceeds it
    double hard_warn = std::numeric_limits<double>::infinity(); ///< warn when any error exceeds it
};

/// The verdict for the sums of one frame (pixel counts made with the fail/warn thresholds).
Verdict judge(const ErrorSums& frame, const VerdictRule& rule);

/// The worse of two verdicts.
Verdict worst(Verdict a, Verdict b);

/// "PASS", "WARNING" or "FAILURE", as idiff prints them.
const char* verdict_name(Verdict verdict);

} // namespace modestack::metrics
