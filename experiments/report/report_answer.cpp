// The report's answer: the grid of cells (geometry or material row ×
// roughness band) with each cell's pick by the decision rule, the cells in
// detail, one leaderboard per row class, and the rows the reference's noise
// leaves unresolved.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "decision_rule.h"
#include "report_document.h"
#include "shimmer/experiments/csv.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments::report {

namespace {

std::string Share(int count, int of) { return std::to_string(count) + "/" + std::to_string(of); }

// The median cost ratio, one per benchmark device (named when there are several).
std::string CostOf(const CellCandidate& c) {
  if (c.cost.empty()) return "n/a";
  std::vector<std::string> parts;
  for (const auto& [device, q] : c.cost)
    parts.push_back(Fmt(q.median, "%.2f") + "×" + (c.cost.size() > 1 ? " on " + device : ""));
  return Join(parts, "; ");
}

std::string GridText(const CellAnswer& cell) {
  if (cell.pick) {
    std::string text = "**" + Code(cell.pick->label) + "** " + Share(cell.pick->better, cell.tables);
    if (cell.runner_up && !cell.pick_ahead) text += " (tied with " + Code(cell.runner_up->label) + ")";
    return text;
  }
  std::string text = "keep `none`";
  for (const CellCandidate& c : cell.candidates)
    if (!c.supersample && c.better > 0) {
      text += " (best: " + Code(c.label) + " " + Share(c.better, cell.tables) + ")";
      break;
    }
  return text;
}

std::string RunnerUpText(const CellAnswer& cell) {
  if (!cell.runner_up) return "none eligible";
  return Code(cell.runner_up->label) + " " + Share(cell.runner_up->better, cell.tables) + ", " +
         (cell.pick_ahead ? "pick ahead" : "tied") + " (joint error below in " + std::to_string(cell.ahead) +
         ", overlapping in " + std::to_string(cell.tied) + ", above in " + std::to_string(cell.behind) + ")";
}

}  // namespace

bool CpuDevice(const std::vector<std::string>& devices) {
  for (const std::string& d : devices)
    if (d.find("llvmpipe") != std::string::npos || d.find("lavapipe") != std::string::npos) return true;
  return false;
}

void AnswerSection(Document& doc, const std::vector<CellAnswer>& cells, const std::vector<std::string>& devices) {
  doc.Heading(2, kAnswerHeading);
  std::vector<std::string> bands;
  for (const std::string& band : RoughnessBands())
    for (const CellAnswer& c : cells)
      if (c.band == band) {
        bands.push_back(band);
        break;
      }
  std::vector<std::string> header = {"geometry or material"};
  header.insert(header.end(), bands.begin(), bands.end());
  std::vector<std::vector<std::string>> rows;
  std::set<std::string> present;
  for (const CellAnswer& c : cells) present.insert(c.row);
  for (const std::string& row : CellRowsInOrder(present)) {
    std::vector<std::string> line = {row};
    bool any = false;
    for (const std::string& band : bands) {
      auto it = std::find_if(cells.begin(), cells.end(),
                             [&](const CellAnswer& c) { return c.row == row && c.band == band; });
      line.push_back(it == cells.end() ? "—" : GridText(*it));
      any |= it != cells.end();
    }
    if (any) rows.push_back(std::move(line));
  }
  doc.Table(header, rows);
  doc.Paragraph(
      "**How to read it.** Each cell names the filter to use for that geometry or material (rows) and roughness "
      "α (columns), with the number of the cell's tables (shots × cameras × derivative sources) in which it is "
      "better than `none`: significantly steadier (the 95 % interval of its `tv_err` minus `none`'s below 0, the "
      "two measured on the same draws so that the reference's noise cancels), not blurrier than " +
      FormatNumber(kSpatialTolerance, "%g") + "× `none`'s spatial error, and within ±" +
      FormatNumber(100 * kEnergyTolerance, "%g") +
      " % of the highlight's energy. A pick is better in at least half of its cell's tables and has the lowest "
      "joint error (`relmse`, flicker and spatial error in one number) among those that are; \"tied with\" names "
      "a runner-up it cannot be told from. **keep `none`**: no filter is better often enough (the best one is "
      "named with its count). The full rule is in the Method section; the cells in detail follow below." +
      (CpuDevice(devices) ? std::string(" Costs in this report are CPU times: lavapipe (llvmpipe) runs the compute "
                                        "shaders on the CPU, so a ratio to `none` is evidence about arithmetic, "
                                        "not a GPU's time.")
                          : std::string()));
}

void CellDetails(Document& doc, const std::vector<CellAnswer>& cells) {
  doc.Heading(3, kCellsHeading);
  std::vector<std::vector<std::string>> rows;
  for (const CellAnswer& c : cells) {
    std::vector<std::string> line = {c.row + ", " + c.band,
                                     std::to_string(c.tables) + " (" + std::to_string(c.shots) + " shots)"};
    if (c.pick) {
      const CellCandidate& p = *c.pick;
      line.insert(line.end(), {"**" + Code(p.label) + "**", Share(p.better, c.tables), Ratio(p.joint_ratio),
                               Fmt(p.energy_bias.median, "%+.3f"), CostOf(p), RunnerUpText(c)});
    } else {
      std::string best = "none is better anywhere";
      for (const CellCandidate& cand : c.candidates)
        if (!cand.supersample && cand.better > 0) {
          best = "most often better: " + Code(cand.label) + " " + Share(cand.better, c.tables);
          break;
        }
      line.insert(line.end(), {"keep `none`", best, "", "", "", ""});
    }
    rows.push_back(std::move(line));
  }
  doc.Table({"cell", "tables", "answer", "better than `none` in", "joint error, ratio to `none` (IQR)",
             "energy bias (fraction)", "cost, ratio to `none`", "runner-up"},
            rows);
}

void ClassLeaderboards(Document& doc, const std::vector<const Group*>& groups) {
  doc.Heading(3, kLeaderboardHeading);
  doc.Paragraph(
      "One table per row of the answer grid, over all its roughness bands; never mixed across classes. Ratios "
      "are to `none` of the same table, medians over the tables with their interquartile range; \"better\" "
      "counts the tables where the decision rule says so.");
  std::map<std::string, std::vector<const Group*>> by_row;
  std::set<std::string> present;
  for (const Group* g : groups) by_row[CellRowOf(*g)].push_back(g);
  for (const auto& [row, members] : by_row) present.insert(row);
  for (const std::string& row : CellRowsInOrder(present)) {
    auto it = by_row.find(row);
    if (it == by_row.end()) continue;
    const int tables = int(it->second.size());
    std::vector<std::vector<std::string>> cells;
    for (const CellCandidate& c : Candidates(it->second))
      cells.push_back({Code(c.label) + (c.supersample ? " (baseline)" : ""), std::to_string(c.tables),
                       Share(c.better, tables), Ratio(c.joint_ratio), Ratio(c.tv_err_ratio),
                       Share(c.energy_within, c.tables), CostOf(c)});
    doc.Heading(4, row + " (" + std::to_string(tables) + " tables)");
    doc.Table({"variant", "tables", "better than `none`", "joint error, ratio to `none`", "tv_err, ratio to `none`",
               "energy within ±10 %", "cost, ratio to `none`"},
              cells);
  }
}

void ReferenceNoiseSection(Document& doc, const std::vector<const Group*>& groups) {
  doc.Heading(3, kReferenceNoiseHeading);
  std::set<const JobResult*> rows, noisy;
  std::map<std::string, int> by_shot;
  int unresolved = 0, faint = 0, compared = 0, paired = 0;
  for (const Group* g : groups) {
    const JobResult* none = NoneOf(*g);
    for (const JobResult* r : g->rows) {
      if (!rows.insert(r).second) continue;
      if (Metric(r->metrics, "tv_err_floor") > kNoiseShareLimit) noisy.insert(r);
      if (!none || r == none) continue;
      const Evidence e = EvidenceOf(*r), base = EvidenceOf(*none);
      ++compared;
      paired += PairedTvErr(e, base).has_value();
      const Outcome outcome = Decide(e, base);
      if (outcome == Outcome::kUnresolved) ++unresolved, ++by_shot[g->Shot()];
      else if (outcome == Outcome::kTied && NoiseBelowVisibility(e, base)) ++faint;
    }
  }
  const double share = rows.empty() ? 0.0 : double(unresolved) / double(rows.size());
  doc.Paragraph(
      std::to_string(noisy.size()) + " of " + std::to_string(rows.size()) + " rows have `tv_err_floor` above " +
      FormatNumber(kNoiseShareLimit, "%g") +
      ": the reference's own noise explains most of their `tv_err`. It explains little of a *comparison*: " +
      std::to_string(paired) + " of the " + std::to_string(compared) +
      " comparisons with `none` are paired (both rows measured on the same bootstrap draws against the same "
      "reference), and in their `tv_err` difference that noise cancels but for a cross term, which widens the "
      "difference's interval (docs/metrics.md, \"Paired intervals\"). A tie is **unresolved: reference noise** "
      "when the noise is over " +
      FormatNumber(100 * kNoiseShareLimit, "%g") +
      " % of what it compares (the paired interval's half-width; unpaired, either row's `tv_err`), unless its "
      "contrast is under " +
      FormatNumber(100 * kVisibleContrast, "%g") + " % (" + std::to_string(faint) +
      " rows: fainter than any visible flicker, the tie stands). " + std::to_string(unresolved) + " rows (" +
      FormatNumber(100 * share, "%.1f") +
      " %) are unresolved; a reference with more samples would resolve them. The aim is at most 5 % of the rows" +
      (share <= 0.05 ? std::string(", met.") : std::string(", not met in this store.")));
  std::vector<std::string> items;
  for (const auto& [shot, count] : by_shot) items.push_back(shot + ": " + std::to_string(count) + " rows");
  if (!items.empty()) doc.List(items);
}

std::string CellsCsv(const std::vector<CellAnswer>& cells) {
  CsvTable table({"row", "band", "tables", "shots", "pick", "pick_better", "runner_up", "runner_up_better",
                  "pick_ahead"});
  for (const CellAnswer& c : cells)
    table.AddRow({c.row, c.band, std::to_string(c.tables), std::to_string(c.shots), c.pick ? c.pick->label : "none",
                  std::to_string(c.pick ? c.pick->better : 0), c.runner_up ? c.runner_up->label : "",
                  std::to_string(c.runner_up ? c.runner_up->better : 0), c.pick_ahead ? "1" : "0"});
  return table.Text();
}

}  // namespace shimmer::experiments::report
