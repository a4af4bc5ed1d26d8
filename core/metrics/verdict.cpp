// idiff's pass/warn/fail rule (see verdict.h).
#include "core/metrics/verdict.h"

namespace modestack::metrics {

Verdict judge(const ErrorSums& frame, const VerdictRule& rule)
{
    double pixels = static_cast<double>(frame.pixels);
    // The same comparisons as idiff: strictly more than the allowed share.
    if (frame.non_finite > 0 ||
        static_cast<double>(frame.pixels_failing) > rule.fail_percent / 100.0 * pixels ||
        frame.max_absolute > rule.hard_fail)
        return Verdict::Failure;
    if (static_cast<double>(frame.pixels_warning) > rule.warn_percent / 100.0 * pixels ||
        frame.max_absolute > rule.hard_warn)
        return Verdict::Warning;
    return Verdict::Pass;
}

Verdict worst(Verdict a, Verdict b)
{
    return static_cast<int>(a) >= static_cast<int>(b) ? a : b;
}

const char* verdict_name(Verdict verdict)
{
    switch (verdict) {
    case Verdict::Pass:
        return "PASS";
    case Verdict::Warning:
        return "WARNING";
    case Verdict::Failure:
        return "FAILURE";
    }
    return "FAILURE";
}

} // namespace modestack::metrics
