// The paper's table rules on hand-made results with known answers: failures, ties, greyed rows,
// all-failed systems and sequences.

#include <doctest/doctest.h>

#include <cmath>
#include <optional>
#include <stdexcept>

#include "voca/eval/results_table.h"

using voca::CellKind;
using voca::RunMetrics;
using voca::RunOutcome;
using voca::TableMetric;

namespace {

constexpr auto kAte = static_cast<std::size_t>(TableMetric::kAte);
constexpr auto kRte = static_cast<std::size_t>(TableMetric::kRte);

std::optional<RunMetrics> ok(double ate, double rte) { return RunMetrics{RunOutcome::kCompleted, ate, rte, 1.0}; }
std::optional<RunMetrics> crashed() { return RunMetrics{RunOutcome::kCrashed, 0.0, std::nullopt, 0.0}; }
std::optional<RunMetrics> resetting(double ate, double rte) {
  return RunMetrics{RunOutcome::kCompleted, ate, rte, 0.4};
}

std::vector<voca::TableSystem> systems(std::initializer_list<const char*> names) {
  std::vector<voca::TableSystem> result;
  for (const char* name : names) result.push_back({name});
  return result;
}

}  // namespace

TEST_CASE("classifyRun applies the paper's thresholds, x and R") {
  const voca::TableRules rules;  // 10 m ATE, 10 cm RTE, R at half
  CHECK(voca::classifyRun(std::nullopt, TableMetric::kAte, rules).kind == CellKind::kMissing);
  CHECK(voca::classifyRun(crashed(), TableMetric::kAte, rules).kind == CellKind::kCrashed);
  CHECK(voca::classifyRun(ok(10.5, 0.01), TableMetric::kAte, rules).kind == CellKind::kDivergent);
  CHECK(voca::classifyRun(ok(10.0, 0.01), TableMetric::kAte, rules).kind == CellKind::kValue);  // not above
  CHECK(voca::classifyRun(ok(0.2, 0.11), TableMetric::kRte, rules).kind == CellKind::kDivergent);
  CHECK(voca::classifyRun(ok(0.2, 0.11), TableMetric::kAte, rules).kind == CellKind::kValue);
  CHECK(voca::classifyRun(resetting(0.2, 0.01), TableMetric::kAte, rules).kind == CellKind::kReset);
  // Divergence is shown before R.
  CHECK(voca::classifyRun(resetting(20.0, 0.01), TableMetric::kAte, rules).kind == CellKind::kDivergent);
  // No RTE pair: incomplete.
  CHECK(voca::classifyRun(RunMetrics{RunOutcome::kCompleted, 0.1, std::nullopt, 1.0}, TableMetric::kRte, rules).kind ==
        CellKind::kCrashed);
  // Small rooms: 1 m.
  voca::TableRules room;
  room.ate_divergence_m = 1.0;
  CHECK(voca::classifyRun(ok(1.5, 0.01), TableMetric::kAte, room).kind == CellKind::kDivergent);
  // Exactly half without a reset is not "more than half".
  CHECK(voca::classifyRun(RunMetrics{RunOutcome::kCompleted, 0.1, 0.01, 0.5}, TableMetric::kAte, rules).kind ==
        CellKind::kReset);
  CHECK(voca::classifyRun(RunMetrics{RunOutcome::kCompleted, 0.1, 0.01, 0.51}, TableMetric::kAte, rules).kind ==
        CellKind::kValue);
}

TEST_CASE("rankRow: ties share bold, the next distinct value is underlined, failures are not ranked") {
  std::vector<voca::TableCell> cells = {{CellKind::kValue, 0.3},
                                        {CellKind::kValue, 0.1},
                                        {CellKind::kDivergent},
                                        {CellKind::kValue, 0.1},
                                        {CellKind::kValue, 0.2}};
  std::vector<voca::TableCell*> row;
  for (auto& cell : cells) row.push_back(&cell);
  voca::rankRow(row);
  CHECK(cells[0].rank == 0);
  CHECK(cells[1].rank == 1);
  CHECK(cells[2].rank == 0);
  CHECK(cells[3].rank == 1);
  CHECK(cells[4].rank == 2);

  // A single system: nothing to compare with.
  voca::TableCell alone{CellKind::kValue, 1.0};
  voca::rankRow({&alone});
  CHECK(alone.rank == 0);
  // One value among failures is still the best.
  voca::TableCell a{CellKind::kCrashed}, b{CellKind::kValue, 2.0};
  voca::rankRow({&a, &b});
  CHECK(a.rank == 0);
  CHECK(b.rank == 1);
}

TEST_CASE("buildResultsTable: AVG over sequences no system failed, MED with failures as infinity, SR") {
  // Three systems on four sequences (ATE m, RTE m).
  //            A            B             C
  // seq1   0.10/0.010   0.20/0.020    0.30/0.030
  // seq2   0.40/0.040   x             0.20/0.020     -> greyed (B crashed)
  // seq3   0.30/0.030   0.10/0.010    0.10/0.010
  // seq4   12.0/0.050   0.50/0.050    R              -> greyed (A ATE divergent, C resets)
  const std::vector<std::vector<std::optional<RunMetrics>>> runs = {
      {ok(0.1, 0.01), ok(0.2, 0.02), ok(0.3, 0.03)},
      {ok(0.4, 0.04), crashed(), ok(0.2, 0.02)},
      {ok(0.3, 0.03), ok(0.1, 0.01), ok(0.1, 0.01)},
      {ok(12.0, 0.05), ok(0.5, 0.05), resetting(0.3, 0.03)},
  };
  const voca::ResultsTable t =
      voca::buildResultsTable(systems({"A", "B", "C"}), {"seq1", "seq2", "seq3", "seq4"}, runs);
  CHECK(t.greyed == std::vector<bool>{false, true, false, true});

  // AVG over seq1 and seq3 only.
  CHECK(t.average[kAte][0].kind == CellKind::kValue);
  CHECK(t.average[kAte][0].value == doctest::Approx(0.2));
  CHECK(t.average[kAte][1].value == doctest::Approx(0.15));
  CHECK(t.average[kAte][2].value == doctest::Approx(0.2));
  CHECK(t.average[kAte][1].rank == 1);
  CHECK(t.average[kAte][0].rank == 2);  // tie with C at 0.2: both second
  CHECK(t.average[kAte][2].rank == 2);
  CHECK(t.average[kRte][1].value == doctest::Approx(0.015));

  // MED over all four, failures as infinity: A {0.1,0.3,0.4,inf} -> 0.35; B {0.1,0.2,0.5,inf} -> 0.35;
  // C {0.1,0.2,0.3,R=inf} -> 0.25.
  CHECK(t.median[kAte][0].value == doctest::Approx(0.35));
  CHECK(t.median[kAte][1].value == doctest::Approx(0.35));
  CHECK(t.median[kAte][2].value == doctest::Approx(0.25));
  CHECK(t.median[kAte][2].rank == 1);
  CHECK(t.median[kAte][0].rank == 2);
  // RTE: A's seq4 RTE 0.05 is fine, so A's RTE median is {0.01,0.03,0.04,0.05} -> 0.035.
  CHECK(t.median[kRte][0].value == doctest::Approx(0.035));

  // SR: A 3/4 ATE but 4/4 RTE, B 3/4, C 3/4.
  CHECK(t.success_rate[kAte] == std::vector<double>{0.75, 0.75, 0.75});
  CHECK(t.success_rate[kRte][0] == doctest::Approx(1.0));
  CHECK(t.success_rank[kRte][0] == 1);
  CHECK(t.success_rank[kRte][1] == 2);
  CHECK(t.success_rank[kAte] == std::vector<int>{1, 1, 1});

  // Cells keep their kinds and per-row ranks.
  CHECK(t.cells[kAte][1][1].kind == CellKind::kCrashed);
  CHECK(t.cells[kRte][1][1].kind == CellKind::kCrashed);
  CHECK(t.cells[kAte][3][0].kind == CellKind::kDivergent);
  CHECK(t.cells[kAte][3][2].kind == CellKind::kReset);
  CHECK(t.cells[kAte][0][0].rank == 1);
  CHECK(t.cells[kAte][0][1].rank == 2);
  CHECK(t.cells[kAte][2][1].rank == 1);  // tie of B and C on seq3
  CHECK(t.cells[kAte][2][2].rank == 1);
  CHECK(t.cells[kAte][2][0].rank == 2);
}

TEST_CASE("buildResultsTable: a system left out of the AVG rule, an all-failed system, all sequences failed") {
  // X fails everywhere (as MoV-SLAM in the paper); with counts_for_avg off it does not grey anything.
  std::vector<voca::TableSystem> s = systems({"X", "Y"});
  s[0].counts_for_avg = {false, false};
  const std::vector<std::vector<std::optional<RunMetrics>>> runs = {
      {ok(20.0, 0.5), ok(0.1, 0.01)},
      {crashed(), ok(0.3, 0.03)},
      {ok(15.0, 0.2), ok(0.2, 0.02)},
  };
  const voca::ResultsTable t = voca::buildResultsTable(s, {"a", "b", "c"}, runs);
  CHECK(t.greyed == std::vector<bool>{false, false, false});
  CHECK(t.average[kAte][0].kind == CellKind::kDivergent);  // the all-failed system's AVG is infinity
  CHECK(t.median[kAte][0].kind == CellKind::kDivergent);
  CHECK(t.success_rate[kAte][0] == 0.0);
  CHECK(t.success_rank[kAte][0] == 0);  // 0 % is not marked
  CHECK(t.average[kAte][1].value == doctest::Approx(0.2));
  CHECK(t.median[kAte][1].value == doctest::Approx(0.2));
  CHECK(t.average[kAte][1].rank == 1);

  // Counted, the same failures grey every sequence: AVG is undefined, MED still shows Y's median.
  s[0].counts_for_avg = {true, true};
  const voca::ResultsTable all_grey = voca::buildResultsTable(s, {"a", "b", "c"}, runs);
  CHECK(all_grey.greyed == std::vector<bool>{true, true, true});
  CHECK(all_grey.average[kAte][0].kind == CellKind::kNotDefined);
  CHECK(all_grey.average[kAte][1].kind == CellKind::kNotDefined);
  CHECK(all_grey.median[kAte][1].value == doctest::Approx(0.2));

  // A system that only resets shows R in its aggregates; a missing result makes them unknown.
  const voca::ResultsTable resets = voca::buildResultsTable(
      systems({"R", "M"}), {"a", "b"}, {{resetting(0.1, 0.01), std::nullopt}, {resetting(0.1, 0.01), ok(0.1, 0.01)}});
  CHECK(resets.median[kAte][0].kind == CellKind::kReset);
  CHECK(resets.median[kAte][1].kind == CellKind::kMissing);
  CHECK(resets.cells[kAte][0][1].kind == CellKind::kMissing);
  CHECK(resets.greyed[0]);  // R on a counted system greys the row

  CHECK_THROWS_AS(voca::buildResultsTable(systems({"A"}), {"a", "b"}, {{ok(0.1, 0.01)}}), std::invalid_argument);
}

TEST_CASE("compareWithBaseline: mean and worst relative change over the sequences both completed") {
  // Baseline B and system M on four sequences: M is 20 % better on a, 10 % worse on b, 4 % worse on c,
  // and diverges on d (ATE beyond 10 m), where B has a value.
  const voca::ResultsTable t = voca::buildResultsTable(systems({"B", "M"}), {"a", "b", "c", "d"},
                                                       {{ok(1.0, 0.010), ok(0.8, 0.008)},
                                                        {ok(2.0, 0.020), ok(2.2, 0.022)},
                                                        {ok(1.0, 0.050), ok(1.04, 0.052)},
                                                        {ok(1.0, 0.010), ok(11.0, 0.0103)}});
  const voca::BaselineComparison ate = voca::compareWithBaseline(t, 1, 0, TableMetric::kAte, 0.05);
  CHECK(ate.compared == 3);
  CHECK(ate.failed_only_system == 1);
  CHECK(ate.failed_only_baseline == 0);
  CHECK(ate.mean_change == doctest::Approx((-0.2 + 0.1 + 0.04) / 3.0));
  CHECK(ate.worst_change == doctest::Approx(0.1));
  CHECK(t.sequences[ate.worst_sequence] == "b");
  CHECK(ate.worse_than_tolerance == 1);  // b; c's 4 % is within 5 %
  // RTE: d has a value for both (1.03 cm is below the 10 cm divergence threshold): 3 % worse.
  const voca::BaselineComparison rte = voca::compareWithBaseline(t, 1, 0, TableMetric::kRte, 0.05);
  CHECK(rte.compared == 4);
  CHECK(rte.mean_change == doctest::Approx((-0.2 + 0.1 + 0.04 + 0.03) / 4.0));
  CHECK(rte.worse_than_tolerance == 1);
  CHECK(t.sequences[rte.worst_sequence] == "b");
  // The other way round the failure is the baseline's, and the changes are those of B against M.
  const voca::BaselineComparison back = voca::compareWithBaseline(t, 0, 1, TableMetric::kAte, 0.05);
  CHECK(back.failed_only_baseline == 1);
  CHECK(back.failed_only_system == 0);
  CHECK(back.worst_change == doctest::Approx(0.25));  // a: 1.0 / 0.8
  // Against itself: every change zero.
  const voca::BaselineComparison self = voca::compareWithBaseline(t, 0, 0, TableMetric::kRte, 0.0);
  CHECK(self.compared == 4);
  CHECK(self.mean_change == 0.0);
  CHECK(self.worse_than_tolerance == 0);
  CHECK_THROWS_AS(voca::compareWithBaseline(t, 2, 0, TableMetric::kAte, 0.05), std::invalid_argument);
}

TEST_CASE("medianOfRepeats: each metric's middle repeat, crashes as the worst, the worse middle of an even count") {
  // Three clean repeats: each metric on its own (ATE from the first, RTE from the third).
  RunMetrics m = voca::medianOfRepeats({*ok(0.05, 0.030), *ok(0.09, 0.010), *ok(0.02, 0.020)});
  CHECK(m.outcome == RunOutcome::kCompleted);
  CHECK(m.ate_m == 0.05);
  REQUIRE(m.rte_m);
  CHECK(*m.rte_m == 0.020);
  CHECK(m.reset_free_fraction == 1.0);

  // One crash of three: the median is the worse of the two that ran.
  m = voca::medianOfRepeats({*ok(0.05, 0.030), *crashed(), *ok(0.02, 0.020)});
  CHECK(m.outcome == RunOutcome::kCompleted);
  CHECK(m.ate_m == 0.05);
  CHECK(*m.rte_m == 0.030);
  CHECK(m.reset_free_fraction == 1.0);

  // Two crashes of three: a crash, shown as x.
  m = voca::medianOfRepeats({*crashed(), *crashed(), *ok(0.02, 0.020)});
  CHECK(m.outcome == RunOutcome::kCrashed);
  CHECK(voca::classifyRun(m, TableMetric::kAte, {}).kind == CellKind::kCrashed);

  // Resets: the fraction's median decides R (two of three reset -> R), the errors stay values.
  m = voca::medianOfRepeats({*resetting(0.01, 0.01), *resetting(0.03, 0.02), *ok(0.02, 0.03)});
  CHECK(m.reset_free_fraction == 0.4);
  CHECK(voca::classifyRun(m, TableMetric::kAte, {}).kind == CellKind::kReset);
  m = voca::medianOfRepeats({*resetting(0.01, 0.01), *ok(0.03, 0.02), *ok(0.02, 0.03)});
  CHECK(m.reset_free_fraction == 1.0);
  CHECK(voca::classifyRun(m, TableMetric::kAte, {}).kind == CellKind::kValue);

  // Even count: the worse middle; a missing RTE counts as infinite.
  m = voca::medianOfRepeats({*ok(0.01, 0.01), *ok(0.04, 0.04), *ok(0.02, 0.02), *ok(0.03, 0.03)});
  CHECK(m.ate_m == 0.03);
  CHECK(*m.rte_m == 0.03);
  m = voca::medianOfRepeats({RunMetrics{RunOutcome::kCompleted, 0.01, std::nullopt, 1.0},
                             RunMetrics{RunOutcome::kCompleted, 0.02, std::nullopt, 1.0}, *ok(0.03, 0.03)});
  CHECK_FALSE(m.rte_m);

  // One repeat is itself.
  m = voca::medianOfRepeats({*resetting(0.07, 0.02)});
  CHECK(m.ate_m == 0.07);
  CHECK(m.reset_free_fraction == 0.4);
  CHECK_THROWS_AS(voca::medianOfRepeats({}), std::invalid_argument);
}

TEST_CASE("buildResultsTable: a sequence's own rules decide its cells, the others keep the suite's") {
  // A street sequence whose 6-frame RTE of 0.3 m is ordinary drift there; the paper's 10 cm elsewhere.
  voca::TableRules street;
  street.rte_divergence_m = 1.0;
  const voca::ResultsTable t =
      voca::buildResultsTable(systems({"A"}), {"room", "street"}, {{ok(0.05, 0.3)}, {ok(5.0, 0.3)}},
                              std::vector<voca::TableRules>{voca::TableRules{}, street});
  CHECK(t.cells[kRte][0][0].kind == CellKind::kDivergent);
  CHECK(t.cells[kRte][1][0].kind == CellKind::kValue);
  CHECK(t.cells[kRte][1][0].value == 0.3);
  CHECK(t.cells[kAte][1][0].kind == CellKind::kValue);
  CHECK_THROWS_AS(voca::buildResultsTable(systems({"A"}), {"room", "street"}, {{ok(0.05, 0.3)}, {ok(5.0, 0.3)}},
                                          std::vector<voca::TableRules>{street}),
                  std::invalid_argument);
}
