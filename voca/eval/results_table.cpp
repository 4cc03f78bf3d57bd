#include "voca/eval/results_table.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace voca {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

bool isFailure(CellKind kind) {
  return kind == CellKind::kDivergent || kind == CellKind::kCrashed || kind == CellKind::kReset;
}

// An aggregate over cells some of which failed: unknown while a result is missing, R when the
// system's trouble is resetting, else infinity (a crash counts as a failure of unbounded error).
CellKind failedAggregateKind(const std::vector<const TableCell*>& cells) {
  bool any_reset = false, all_failures_reset = true;
  for (const TableCell* cell : cells) {
    if (cell->kind == CellKind::kMissing) return CellKind::kMissing;
    if (cell->kind == CellKind::kReset) any_reset = true;
    if (isFailure(cell->kind) && cell->kind != CellKind::kReset) all_failures_reset = false;
  }
  return any_reset && all_failures_reset ? CellKind::kReset : CellKind::kDivergent;
}

TableCell average(const std::vector<const TableCell*>& cells) {
  if (cells.empty()) return {CellKind::kNotDefined};
  double sum = 0.0;
  for (const TableCell* cell : cells) {
    if (cell->kind != CellKind::kValue) return {failedAggregateKind(cells)};
    sum += cell->value;
  }
  return {CellKind::kValue, sum / static_cast<double>(cells.size())};
}

TableCell median(const std::vector<const TableCell*>& cells) {
  if (cells.empty()) return {CellKind::kNotDefined};
  std::vector<double> values;
  for (const TableCell* cell : cells) {
    if (cell->kind == CellKind::kMissing) return {CellKind::kMissing};
    values.push_back(cell->kind == CellKind::kValue ? cell->value : kInfinity);
  }
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  const double middle = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  if (std::isinf(middle)) return {failedAggregateKind(cells)};
  return {CellKind::kValue, middle};
}

}  // namespace

TableCell classifyRun(const std::optional<RunMetrics>& run, TableMetric metric, const TableRules& rules) {
  if (!run) return {CellKind::kMissing};
  if (run->outcome == RunOutcome::kCrashed) return {CellKind::kCrashed};
  const bool ate = metric == TableMetric::kAte;
  if (!ate && !run->rte_m) return {CellKind::kCrashed};  // too short for one pair: incomplete
  const double value = ate ? run->ate_m : *run->rte_m;
  if (!std::isfinite(value) || value > (ate ? rules.ate_divergence_m : rules.rte_divergence_m)) {
    return {CellKind::kDivergent};
  }
  if (run->reset_free_fraction <= rules.min_reset_free_fraction) return {CellKind::kReset};
  return {CellKind::kValue, value};
}

void rankRow(std::vector<TableCell*> row) {
  for (TableCell* cell : row) cell->rank = 0;
  if (row.size() < 2) return;
  std::vector<double> values;
  for (const TableCell* cell : row) {
    if (cell->kind == CellKind::kValue) values.push_back(cell->value);
  }
  if (values.empty()) return;
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  for (TableCell* cell : row) {
    if (cell->kind != CellKind::kValue) continue;
    if (cell->value == values[0]) {
      cell->rank = 1;
    } else if (values.size() > 1 && cell->value == values[1]) {
      cell->rank = 2;
    }
  }
}

ResultsTable buildResultsTable(std::vector<TableSystem> systems, std::vector<std::string> sequences,
                               const std::vector<std::vector<std::optional<RunMetrics>>>& runs,
                               const TableRules& rules) {
  const std::size_t count = sequences.size();
  return buildResultsTable(std::move(systems), std::move(sequences), runs, std::vector<TableRules>(count, rules));
}

ResultsTable buildResultsTable(std::vector<TableSystem> systems, std::vector<std::string> sequences,
                               const std::vector<std::vector<std::optional<RunMetrics>>>& runs,
                               const std::vector<TableRules>& rules_per_sequence) {
  if (runs.size() != sequences.size()) {
    throw std::invalid_argument("buildResultsTable: one row of runs per sequence expected");
  }
  if (rules_per_sequence.size() != sequences.size()) {
    throw std::invalid_argument("buildResultsTable: one set of rules per sequence expected");
  }
  for (const auto& row : runs) {
    if (row.size() != systems.size()) throw std::invalid_argument("buildResultsTable: one run per system expected");
  }
  ResultsTable table;
  table.systems = std::move(systems);
  table.sequences = std::move(sequences);
  const std::size_t num_systems = table.systems.size(), num_sequences = table.sequences.size();
  table.greyed.assign(num_sequences, false);

  for (std::size_t m = 0; m < kNumTableMetrics; ++m) {
    auto& cells = table.cells[m];
    cells.assign(num_sequences, std::vector<TableCell>(num_systems));
    for (std::size_t q = 0; q < num_sequences; ++q) {
      for (std::size_t s = 0; s < num_systems; ++s) {
        cells[q][s] = classifyRun(runs[q][s], static_cast<TableMetric>(m), rules_per_sequence[q]);
        if (isFailure(cells[q][s].kind) && table.systems[s].counts_for_avg[m]) table.greyed[q] = true;
      }
    }
  }

  for (std::size_t m = 0; m < kNumTableMetrics; ++m) {
    auto& cells = table.cells[m];
    table.average[m].resize(num_systems);
    table.median[m].resize(num_systems);
    table.success_rate[m].assign(num_systems, 0.0);
    table.success_rank[m].assign(num_systems, 0);
    for (std::size_t s = 0; s < num_systems; ++s) {
      std::vector<const TableCell*> kept, all;
      std::size_t successes = 0;
      for (std::size_t q = 0; q < num_sequences; ++q) {
        all.push_back(&cells[q][s]);
        if (!table.greyed[q]) kept.push_back(&cells[q][s]);
        if (cells[q][s].kind == CellKind::kValue) ++successes;
      }
      table.average[m][s] = average(kept);
      table.median[m][s] = median(all);
      if (num_sequences > 0) {
        table.success_rate[m][s] = static_cast<double>(successes) / static_cast<double>(num_sequences);
      }
    }
    for (auto& row : cells) {
      std::vector<TableCell*> pointers;
      for (TableCell& cell : row) pointers.push_back(&cell);
      rankRow(pointers);
    }
    for (auto* aggregate : {&table.average[m], &table.median[m]}) {
      std::vector<TableCell*> pointers;
      for (TableCell& cell : *aggregate) pointers.push_back(&cell);
      rankRow(pointers);
    }
    // Success rate: the highest is best; the same rule with the sign flipped.
    std::vector<TableCell> rates(num_systems);
    std::vector<TableCell*> pointers;
    for (std::size_t s = 0; s < num_systems; ++s) {
      // A rate of zero is not an achievement to mark.
      rates[s] = {table.success_rate[m][s] > 0.0 ? CellKind::kValue : CellKind::kDivergent, -table.success_rate[m][s]};
      pointers.push_back(&rates[s]);
    }
    rankRow(pointers);
    for (std::size_t s = 0; s < num_systems; ++s) table.success_rank[m][s] = rates[s].rank;
  }
  return table;
}

RunMetrics medianOfRepeats(const std::vector<RunMetrics>& repeats) {
  if (repeats.empty()) throw std::invalid_argument("medianOfRepeats: no repeats");
  // Sorted ascending, the worse middle value of an even count is at size / 2.
  const auto middle = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
  };
  std::vector<double> ate, rte, reset_free;
  for (const RunMetrics& r : repeats) {
    const bool crashed = r.outcome == RunOutcome::kCrashed;
    ate.push_back(crashed ? kInfinity : r.ate_m);
    rte.push_back(crashed || !r.rte_m ? kInfinity : *r.rte_m);
    reset_free.push_back(crashed ? kInfinity : -r.reset_free_fraction);  // negated: a lower fraction is worse
  }
  RunMetrics result;
  result.ate_m = middle(ate);
  if (std::isinf(result.ate_m)) return RunMetrics{RunOutcome::kCrashed, 0.0, std::nullopt, 0.0};
  const double median_rte = middle(rte);
  if (!std::isinf(median_rte)) result.rte_m = median_rte;
  const double median_reset_free = middle(reset_free);
  result.reset_free_fraction = std::isinf(median_reset_free) ? 0.0 : -median_reset_free;
  return result;
}

BaselineComparison compareWithBaseline(const ResultsTable& table, std::size_t system, std::size_t baseline,
                                       TableMetric metric, double tolerance) {
  if (system >= table.systems.size() || baseline >= table.systems.size()) {
    throw std::invalid_argument("compareWithBaseline: no such system in the table");
  }
  const auto& cells = table.cells[static_cast<std::size_t>(metric)];
  BaselineComparison result;
  double sum = 0.0;
  for (std::size_t q = 0; q < cells.size(); ++q) {
    const TableCell& mine = cells[q][system];
    const TableCell& base = cells[q][baseline];
    if (base.kind == CellKind::kValue && isFailure(mine.kind)) ++result.failed_only_system;
    if (mine.kind == CellKind::kValue && isFailure(base.kind)) ++result.failed_only_baseline;
    if (mine.kind != CellKind::kValue || base.kind != CellKind::kValue || !(base.value > 0.0)) continue;
    const double change = mine.value / base.value - 1.0;
    if (result.compared == 0 || change > result.worst_change) {
      result.worst_change = change;
      result.worst_sequence = q;
    }
    if (change > tolerance) ++result.worse_than_tolerance;
    sum += change;
    ++result.compared;
  }
  if (result.compared > 0) result.mean_change = sum / static_cast<double>(result.compared);
  return result;
}

}  // namespace voca
