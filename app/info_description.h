// How `modestack info` shows what it found: a text description on stdout (like
// exrheader for a whole shot) and the same facts as JSON for `--json`, both
// with every part's channels and every frame's check.
#pragma once

#include "app/info_job.h"

#include <nlohmann/json.hpp>

namespace modestack::app {

/// Prints the description of `findings` on stdout; attribute values longer than
/// 72 characters are cut unless `all_attributes`.
void print_info(const InfoFindings& findings, bool all_attributes);

/// The description of `findings` as JSON.
nlohmann::ordered_json info_json(const InfoFindings& findings);

} // namespace modestack::app
