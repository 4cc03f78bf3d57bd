#pragma once
// The paper's result tables (DESIGN.md section 7) as plain data: per-sequence ATE and RTE of several
// systems with the failure rules (infinity for divergence, x for crashes, R for resets), AVG over the
// sequences no system failed, MED with failures as infinity, success rate, best and second best.
// Rendering (Markdown, CSV, LaTeX) lives with the tools; this is only the arithmetic.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace voca {

// What became of one run of one system on one sequence.
enum class RunOutcome {
  kCompleted,  // produced a trajectory that was evaluated
  kCrashed,    // crashed, failed or stopped before the end: shown as x
};

// One run's measurements. ate_m / rte_m are RMSEs in metres; rte_m is empty when the trajectory was
// too short for one relative pair. reset_free_fraction is the longest stretch of the expected frames
// estimated without a reset or a gap (1 = the whole sequence in one piece).
struct RunMetrics {
  RunOutcome outcome = RunOutcome::kCompleted;
  double ate_m = 0.0;
  std::optional<double> rte_m;
  double reset_free_fraction = 1.0;
};

// The paper's thresholds (Table 1; use ate_divergence_m = 1 for small rooms such as the Monado set).
struct TableRules {
  double ate_divergence_m = 10.0;
  double rte_divergence_m = 0.10;
  double min_reset_free_fraction = 0.5;  // R when the longest reset-free stretch is at most this
};

enum class TableMetric { kAte = 0, kRte = 1 };
inline constexpr std::size_t kNumTableMetrics = 2;

// How a cell is shown.
enum class CellKind {
  kValue,       // a number (metres)
  kDivergent,   // infinity
  kCrashed,     // x
  kReset,       // R
  kMissing,     // no result (not run yet)
  kNotDefined,  // an aggregate over nothing (AVG when every sequence is greyed)
};

struct TableCell {
  CellKind kind = CellKind::kMissing;
  double value = 0.0;  // metres for kValue
  int rank = 0;        // 1 = best of its row (bold), 2 = second (underlined), 0 = neither
};

// A system (a column group of the paper's tables): a VOCA-RT mode or an external system.
struct TableSystem {
  std::string name;
  // Whether its failures grey out a sequence, per metric. The paper leaves out systems that give no
  // reasonable values at all (MoV-SLAM; ORB-SLAM3's RTE), so that one system does not empty the AVG.
  std::array<bool, kNumTableMetrics> counts_for_avg{true, true};
};

// The table: cells[metric][sequence][system], aggregates[metric][system].
struct ResultsTable {
  std::vector<TableSystem> systems;
  std::vector<std::string> sequences;
  std::array<std::vector<std::vector<TableCell>>, kNumTableMetrics> cells;
  std::vector<bool> greyed;  // per sequence: some counted system failed on it (left out of AVG)
  std::array<std::vector<TableCell>, kNumTableMetrics> average;
  std::array<std::vector<TableCell>, kNumTableMetrics> median;
  std::array<std::vector<double>, kNumTableMetrics> success_rate;  // 0..1: cells that are kValue
  std::array<std::vector<int>, kNumTableMetrics> success_rank;     // 1 best, 2 second (highest rate)
};

// The cell one run gets under the rules: divergence beats R, R beats a value.
TableCell classifyRun(const std::optional<RunMetrics>& run, TableMetric metric, const TableRules& rules);

// One result from repeats of the same run (the harness repeats a run from a few frames later, since a
// deterministic VO's error moves a lot with small changes of its input). Each of ATE, RTE and the
// reset-free fraction is the median over the repeats on its own, a crashed repeat counting as the
// worst (infinite error, fraction 0) and a missing RTE as infinite; the result is a crash when that
// median of ATE is. With an even count the worse of the two middle values is taken. Throws
// std::invalid_argument for no repeats.
RunMetrics medianOfRepeats(const std::vector<RunMetrics>& repeats);

// runs[sequence][system]: empty optionals are runs without a result. Throws std::invalid_argument when
// the shape does not match the names.
ResultsTable buildResultsTable(std::vector<TableSystem> systems, std::vector<std::string> sequences,
                               const std::vector<std::vector<std::optional<RunMetrics>>>& runs,
                               const TableRules& rules = {});
// The same with each sequence's own rules (rules_per_sequence[q] for sequence q): the paper's bounds
// suit its datasets (and 1 m ATE for small rooms); on a street sequence 6 frames span metres, and an
// RTE of 10 cm there is ordinary drift, not divergence. Throws std::invalid_argument on a size mismatch.
ResultsTable buildResultsTable(std::vector<TableSystem> systems, std::vector<std::string> sequences,
                               const std::vector<std::vector<std::optional<RunMetrics>>>& runs,
                               const std::vector<TableRules>& rules_per_sequence);

// One system of a table against another of the same table, one metric (e.g. a prior mode against
// `none`): the per-sequence relative change system / baseline - 1 over the sequences where both have a
// value (negative = lower error than the baseline).
struct BaselineComparison {
  std::size_t compared = 0;            // sequences where both have a value
  std::size_t failed_only_system = 0;  // the system failed (infinity, x, R) where the baseline has a value
  std::size_t failed_only_baseline = 0;
  double mean_change = 0.0;              // mean of the per-sequence changes (0 when none compared)
  double worst_change = 0.0;             // the largest change
  std::size_t worst_sequence = 0;        // its index in table.sequences
  std::size_t worse_than_tolerance = 0;  // sequences whose change exceeds the tolerance
};

// Throws std::invalid_argument when an index is out of range.
BaselineComparison compareWithBaseline(const ResultsTable& table, std::size_t system, std::size_t baseline,
                                       TableMetric metric, double tolerance);

// Marks the lowest value of a row rank 1 (all ties) and the next distinct value rank 2; failures and
// missing cells are not ranked. Nothing is ranked when fewer than two cells hold values.
void rankRow(std::vector<TableCell*> row);

}  // namespace voca
