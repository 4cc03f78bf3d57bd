#pragma once
// The paper's tables (voca/eval/results_table.h) as text: Markdown for reading, CSV for scripts and
// LaTeX (booktabs) for papers. Values in centimetres as the paper prints them (ATE 2 decimals, RTE 3).

#include <string>

#include "voca/eval/results_table.h"

namespace voca::harness {

// A cell's text without emphasis: "12.34", "∞"/"$\infty$", "x", "R", "?" (no result yet), "–".
enum class TextStyle { kPlain, kLatex };
std::string cellText(const TableCell& cell, TableMetric metric, TextStyle style);

// Markdown: best **bold**, second <u>underlined</u>, greyed sequences in italics with a † mark.
std::string tableMarkdown(const ResultsTable& table, const std::string& title, const TableRules& rules);
// CSV: one row per sequence and aggregate; for each system and metric the value in metres (empty on
// failure), the shown text and the rank.
std::string tableCsv(const ResultsTable& table);
// LaTeX with booktabs: \textbf, \underline, \color{gray} (needs xcolor), $\infty$, $\times$, R.
std::string tableLatex(const ResultsTable& table, const std::string& caption, const TableRules& rules);

}  // namespace voca::harness
