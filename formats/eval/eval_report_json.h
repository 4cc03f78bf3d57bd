#pragma once
// An evaluation report as JSON, as `voca eval --json` and the run summaries write it.

#include <nlohmann/json_fwd.hpp>

#include "voca/eval/evaluate.h"

namespace voca {

// The report as JSON (statistics in metres, verdicts as "ok" / "divergent" / "R").
nlohmann::json evalReportToJson(const EvalReport& report, const EvalOptions& options);

}  // namespace voca
