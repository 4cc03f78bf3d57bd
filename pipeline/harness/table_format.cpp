#include "pipeline/harness/table_format.h"

#include <fmt/core.h>

namespace voca::harness {

namespace {

constexpr std::size_t kMetrics[] = {static_cast<std::size_t>(TableMetric::kAte),
                                    static_cast<std::size_t>(TableMetric::kRte)};

std::string percent(double rate) { return fmt::format("{:.1f}%", 100.0 * rate); }

std::string latexEscape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '_' || c == '%' || c == '&' || c == '#') out += '\\';
    out += c;
  }
  return out;
}

std::string markdownCell(const TableCell& cell, TableMetric metric) {
  const std::string text = cellText(cell, metric, TextStyle::kPlain);
  if (cell.rank == 1) return "**" + text + "**";
  if (cell.rank == 2) return "<u>" + text + "</u>";
  return text;
}

std::string latexCell(const TableCell& cell, TableMetric metric, bool grey) {
  std::string text = cellText(cell, metric, TextStyle::kLatex);
  if (cell.rank == 1) text = "\\textbf{" + text + "}";
  if (cell.rank == 2) text = "\\underline{" + text + "}";
  return grey ? "\\color{gray}" + text : text;
}

std::string rateText(double rate, int rank, bool latex) {
  std::string text = latex ? fmt::format("{:.1f}\\%", 100.0 * rate) : percent(rate);
  if (rank == 1) return latex ? "\\textbf{" + text + "}" : "**" + text + "**";
  if (rank == 2) return latex ? "\\underline{" + text + "}" : "<u>" + text + "</u>";
  return text;
}

}  // namespace

std::string cellText(const TableCell& cell, TableMetric metric, TextStyle style) {
  const bool latex = style == TextStyle::kLatex;
  switch (cell.kind) {
    case CellKind::kValue:
      return metric == TableMetric::kAte ? fmt::format("{:.2f}", 100.0 * cell.value)
                                         : fmt::format("{:.3f}", 100.0 * cell.value);
    case CellKind::kDivergent:
      return latex ? "$\\infty$" : "∞";
    case CellKind::kCrashed:
      return latex ? "$\\times$" : "x";
    case CellKind::kReset:
      return "R";
    case CellKind::kMissing:
      return "?";
    case CellKind::kNotDefined:
      return latex ? "--" : "–";
  }
  return "";
}

std::string tableMarkdown(const ResultsTable& table, const std::string& title, const TableRules& rules) {
  const std::size_t n = table.systems.size();
  std::string md = fmt::format("### {}\n\n", title);
  md += "| sequence |";
  for (const char* metric : {"ATE", "RTE"}) {
    for (const TableSystem& system : table.systems) md += fmt::format(" {} {} |", metric, system.name);
  }
  md += "\n|---|";
  for (std::size_t i = 0; i < 2 * n; ++i) md += "---:|";
  md += "\n";
  for (std::size_t q = 0; q < table.sequences.size(); ++q) {
    const bool grey = table.greyed[q];
    md += grey ? fmt::format("| *{}* † |", table.sequences[q]) : fmt::format("| {} |", table.sequences[q]);
    for (const std::size_t m : kMetrics) {
      for (std::size_t s = 0; s < n; ++s) {
        md += fmt::format(" {} |", markdownCell(table.cells[m][q][s], static_cast<TableMetric>(m)));
      }
    }
    md += "\n";
  }
  for (const auto& [label, aggregate] : {std::pair{"AVG", &table.average}, std::pair{"MED", &table.median}}) {
    md += fmt::format("| **{}** |", label);
    for (const std::size_t m : kMetrics) {
      for (std::size_t s = 0; s < n; ++s)
        md += fmt::format(" {} |", markdownCell((*aggregate)[m][s], static_cast<TableMetric>(m)));
    }
    md += "\n";
  }
  md += "| **SR** |";
  for (const std::size_t m : kMetrics) {
    for (std::size_t s = 0; s < n; ++s)
      md += fmt::format(" {} |", rateText(table.success_rate[m][s], table.success_rank[m][s], false));
  }
  md += fmt::format(
      "\n\nATE [cm] (SE3 aligned) and RTE [cm] (delta 6 frames). ∞: divergent (ATE > {} m or RTE > {} cm); x: crashed "
      "or incomplete; R: no stretch of more than {:.0f}% of the frames without a reset; ?: no result yet. AVG over the "
      "sequences no system failed (the others are marked †), MED over all with failures as ∞, SR: success rate. Best "
      "**bold**, second <u>underlined</u>.\n",
      rules.ate_divergence_m, 100.0 * rules.rte_divergence_m, 100.0 * rules.min_reset_free_fraction);
  return md;
}

std::string tableCsv(const ResultsTable& table) {
  std::string csv = "row,greyed";
  for (const char* metric : {"ate", "rte"}) {
    for (const TableSystem& system : table.systems) {
      csv += fmt::format(",\"{0} {1}_m\",\"{0} {1}_shown\",\"{0} {1}_rank\"", metric, system.name);
    }
  }
  csv += "\n";
  const auto cells = [&](const std::string& label, bool grey, auto&& cellAt) {
    csv += fmt::format("{},{}", label, grey ? 1 : 0);
    for (const std::size_t m : kMetrics) {
      for (std::size_t s = 0; s < table.systems.size(); ++s) {
        const TableCell& cell = cellAt(m, s);
        csv += cell.kind == CellKind::kValue ? fmt::format(",{:.9g}", cell.value) : std::string(",");
        csv += fmt::format(",{},{}", cellText(cell, static_cast<TableMetric>(m), TextStyle::kPlain), cell.rank);
      }
    }
    csv += "\n";
  };
  for (std::size_t q = 0; q < table.sequences.size(); ++q) {
    cells(table.sequences[q], table.greyed[q],
          [&](std::size_t m, std::size_t s) -> const TableCell& { return table.cells[m][q][s]; });
  }
  cells("AVG", false, [&](std::size_t m, std::size_t s) -> const TableCell& { return table.average[m][s]; });
  cells("MED", false, [&](std::size_t m, std::size_t s) -> const TableCell& { return table.median[m][s]; });
  csv += "SR,0";
  for (const std::size_t m : kMetrics) {
    for (std::size_t s = 0; s < table.systems.size(); ++s) {
      csv += fmt::format(",{:.6g},{},{}", table.success_rate[m][s], percent(table.success_rate[m][s]),
                         table.success_rank[m][s]);
    }
  }
  csv += "\n";
  return csv;
}

std::string tableLatex(const ResultsTable& table, const std::string& caption, const TableRules& rules) {
  const std::size_t n = table.systems.size();
  std::string tex = "% needs \\usepackage{booktabs,xcolor}\n\\begin{table}[t]\n\\centering\n";
  tex += fmt::format(
      "\\caption{{{} ATE and RTE ($\\Delta = 6$ frames) in cm; $\\infty$: ATE $>$ {}\\,m or RTE $>$ {}\\,cm; "
      "$\\times$: crashed; R: reset over more than half the trajectory. AVG over the sequences no system failed "
      "(others in gray).}}\n",
      latexEscape(caption), rules.ate_divergence_m, 100.0 * rules.rte_divergence_m);
  tex += "\\begin{tabular}{r " + std::string(n, 'r') + " p{6pt} " + std::string(n, 'r') + "}\n\\toprule\n";
  tex += fmt::format(
      " & \\multicolumn{{{0}}}{{c}}{{ATE [cm] (SE3 aligned)}} & & \\multicolumn{{{0}}}{{c}}{{RTE [cm] "
      "($\\Delta = 6$ frames)}} \\\\\n",
      n);
  tex += fmt::format("\\cmidrule{{2-{}}} \\cmidrule{{{}-{}}}\n", n + 1, n + 3, 2 * n + 2);
  std::string header;
  for (const TableSystem& system : table.systems) header += " & " + latexEscape(system.name);
  tex += header + " &" + header + " \\\\\n\\midrule\n";
  const auto row = [&](const std::string& label, bool grey, auto&& cellAt) {
    tex += grey ? "\\color{gray}" + latexEscape(label) : latexEscape(label);
    for (const std::size_t m : kMetrics) {
      if (m == 1) tex += " &";
      for (std::size_t s = 0; s < n; ++s)
        tex += fmt::format(" & {}", latexCell(cellAt(m, s), static_cast<TableMetric>(m), grey));
    }
    tex += " \\\\\n";
  };
  for (std::size_t q = 0; q < table.sequences.size(); ++q) {
    row(table.sequences[q], table.greyed[q],
        [&](std::size_t m, std::size_t s) -> const TableCell& { return table.cells[m][q][s]; });
  }
  tex += "\\midrule\n";
  row("AVG", false, [&](std::size_t m, std::size_t s) -> const TableCell& { return table.average[m][s]; });
  row("MED", false, [&](std::size_t m, std::size_t s) -> const TableCell& { return table.median[m][s]; });
  tex += "SR";
  for (const std::size_t m : kMetrics) {
    if (m == 1) tex += " &";
    for (std::size_t s = 0; s < n; ++s)
      tex += fmt::format(" & {}", rateText(table.success_rate[m][s], table.success_rank[m][s], true));
  }
  tex += " \\\\\n\\bottomrule\n\\end{tabular}\n\\end{table}\n";
  return tex;
}

}  // namespace voca::harness
