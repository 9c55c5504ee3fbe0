// Writers of lmd-eval retrieval's outputs: results.json (the contract of
// issue 5), report.md (the paper's tables and ours) and SVG plots.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/eval/retrieval.h"
#include "core/render/svg_writer.h"

namespace lmd::eval {
namespace {

std::string Fmt(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string SummaryJson(const RetrievalSummary& s) {
  std::string j = "{";
  auto add = [&](const char* k, double v, bool last = false) {
    j += std::string("\"") + k + "\": " + JsonNumber(v) + (last ? "" : ", ");
  };
  add("queries", static_cast<double>(s.queries));
  add("candidates_mean", s.candidates_mean);
  add("anr", s.anr);
  add("recall_at_1", s.recall_at_1);
  add("top1", s.top1);
  add("top5", s.top5);
  add("top10", s.top10);
  add("top1_count", static_cast<double>(s.top1_count));
  add("top5_count", static_cast<double>(s.top5_count));
  add("top10_count", static_cast<double>(s.top10_count));
  add("place_queries", static_cast<double>(s.place_queries));
  add("place_at_1", s.place_at_1);
  add("place_at_5", s.place_at_5);
  add("pose_count", static_cast<double>(s.pose_count));
  add("pose_err_m_median", s.pose_err_m_median);
  add("pose_err_m_p90", s.pose_err_m_p90);
  add("pose_err_deg_median", s.pose_err_deg_median);
  add("pose_err_deg_p90", s.pose_err_deg_p90);
  add("ms_per_query", s.ms_per_query, true);
  return j + "}";
}

std::string ChangeJson(const ChangeResult& c) {
  std::string j = "{\"tasks\": " + std::to_string(c.tasks) + ", \"success_at_1\": " + JsonNumber(c.success_at_1) +
                  ", \"success_at_10\": " + JsonNumber(c.success_at_10) +
                  ", \"false_alarm_rate\": " + JsonNumber(c.false_alarm_rate) +
                  ", \"masks_mean\": " + JsonNumber(c.masks_mean) + ", \"k\": [";
  for (size_t i = 0; i < c.ks.size(); ++i) j += (i ? ", " : "") + std::to_string(c.ks[i]);
  j += "], \"curves\": {";
  bool first = true;
  for (const auto& [t, curve] : c.curves) {
    j += std::string(first ? "" : ", ") + "\"" + Fmt("%g", t) + "\": [";
    for (size_t i = 0; i < curve.size(); ++i) j += (i ? ", " : "") + JsonNumber(curve[i]);
    j += "]";
    first = false;
  }
  return j + "}}";
}

std::vector<RetrievalSummary> Column(const std::vector<DatasetResults>& ds, const std::string& key) {
  std::vector<RetrievalSummary> v;
  for (const DatasetResults& d : ds) {
    auto it = d.methods.find(key);
    if (it != d.methods.end()) v.push_back(it->second);
  }
  return v;
}

ChangeResult AverageChange(const std::vector<DatasetResults>& ds) {
  ChangeResult o;
  size_t n = 0;
  for (const DatasetResults& d : ds) {
    if (d.change_method.empty() || d.change.tasks == 0) continue;
    ++n;
    const ChangeResult& c = d.change;
    o.tasks += c.tasks;
    o.ks = c.ks;
    o.success_at_1 += c.success_at_1, o.success_at_10 += c.success_at_10;
    o.false_alarm_rate += c.false_alarm_rate, o.masks_mean += c.masks_mean;
    for (const auto& [t, curve] : c.curves) {
      std::vector<double>& acc = o.curves[t];
      acc.resize(curve.size(), 0.0);
      for (size_t i = 0; i < curve.size(); ++i) acc[i] += curve[i];
    }
  }
  if (n == 0) return o;
  o.success_at_1 /= n, o.success_at_10 /= n, o.false_alarm_rate /= n, o.masks_mean /= n;
  for (auto& [t, curve] : o.curves) {
    for (double& v : curve) v /= n;
  }
  return o;
}

// `key`'s change detection at the default threshold (success@1, @10, false
// alarms) averaged over datasets; tasks summed. No tasks: not evaluated.
ChangeResult AverageMethodChange(const std::vector<DatasetResults>& ds, const std::string& key) {
  ChangeResult o;
  size_t n = 0;
  for (const DatasetResults& d : ds) {
    const auto it = d.method_change.find(key);
    if (it == d.method_change.end() || it->second.tasks == 0) continue;
    const ChangeResult& c = it->second;
    o.tasks += c.tasks, ++n;
    o.success_at_1 += c.success_at_1, o.success_at_10 += c.success_at_10, o.false_alarm_rate += c.false_alarm_rate;
  }
  if (n > 0) o.success_at_1 /= n, o.success_at_10 /= n, o.false_alarm_rate /= n;
  return o;
}

// "s@1 / s@10" of `key`'s change detection, or "-" for a method without it.
std::string MethodChangeCell(const std::vector<DatasetResults>& ds, const std::string& key) {
  const ChangeResult c = AverageMethodChange(ds, key);
  return c.tasks == 0 ? "-" : Fmt("%.2f", c.success_at_1) + " / " + Fmt("%.2f", c.success_at_10);
}

std::string ResultsJson(const std::vector<MethodSpec>& specs, const std::vector<DatasetResults>& ds,
                        const RunInfo& info) {
  std::string j = "{\n\"run\": {\"command\": \"" + info.command + "\", \"date\": \"" + info.date +
                  "\", \"seed\": " + std::to_string(info.seed) + ", \"threads\": " + std::to_string(info.threads) +
                  ", \"seconds\": " + JsonNumber(info.seconds) + "},\n";
  auto section = [&](const std::string& name, bool ablation) {
    std::string s = "\"" + name + "\": {\"datasets\": {";
    if (!ablation) s = "\"datasets\": {";
    for (size_t i = 0; i < ds.size(); ++i) {
      s += std::string(i ? ",\n  " : "\n  ") + "\"" + ds[i].name + "\": {";
      bool first = true;
      for (const MethodSpec& m : specs) {
        if ((m.group == "ablation") != ablation) continue;
        auto it = ds[i].methods.find(m.key);
        if (it == ds[i].methods.end()) continue;
        s += std::string(first ? "" : ",\n    ") + "\"" + m.key + "\": " + SummaryJson(it->second);
        first = false;
      }
      s += "}";
    }
    s += "},\n\"overall\": {";
    bool first = true;
    for (const MethodSpec& m : specs) {
      if ((m.group == "ablation") != ablation) continue;
      s += std::string(first ? "\n  " : ",\n  ") + "\"" + m.key + "\": " + SummaryJson(AverageOverDatasets(Column(ds, m.key)));
      first = false;
    }
    s += "}";
    if (ablation) s += "}";
    return s;
  };
  j += section("", false) + ",\n";
  j += "\"change\": {\"method\": \"" + (ds.empty() ? std::string() : ds[0].change_method) +
       "\", \"threshold\": " + JsonNumber(kDefaultChangeThreshold) + ", \"radius_m\": 0.5, \"datasets\": {";
  bool first = true;
  for (const DatasetResults& d : ds) {
    if (d.change_method.empty()) continue;
    j += std::string(first ? "\n  " : ",\n  ") + "\"" + d.name + "\": " + ChangeJson(d.change);
    first = false;
  }
  j += "},\n  \"overall\": " + ChangeJson(AverageChange(ds)) + ",\n  \"by_method\": {";
  // Every method with change evaluation (best and change ablations), averaged over datasets.
  first = true;
  for (const MethodSpec& m : specs) {
    const ChangeResult c = AverageMethodChange(ds, m.key);
    if (c.tasks == 0) continue;
    j += std::string(first ? "\n    " : ",\n    ") + "\"" + m.key + "\": {\"tasks\": " + std::to_string(c.tasks) +
         ", \"success_at_1\": " + JsonNumber(c.success_at_1) + ", \"success_at_10\": " + JsonNumber(c.success_at_10) +
         ", \"false_alarm_rate\": " + JsonNumber(c.false_alarm_rate) + "}";
    first = false;
  }
  j += "}},\n";
  j += section("ablation", true) + "\n}\n";
  return j;
}

// ---------------------------------------------------------------------------
// Markdown.

std::string Pct(double v) { return Fmt("%.1f", v); }
std::string Rate(double v) { return Fmt("%.2f", v); }

std::string OverallTable(const std::vector<MethodSpec>& specs, const std::vector<DatasetResults>& ds,
                         const std::vector<std::string>& groups) {
  std::string t =
      "| method | queries | mean candidates | ANR % | recall@1 | top-1 % | top-5 % | top-10 % | place@1 | place@5 | "
      "pose err m (median / p90) | pose err deg (median / p90) | ms/query |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MethodSpec& m : specs) {
    if (std::find(groups.begin(), groups.end(), m.group) == groups.end()) continue;
    const RetrievalSummary s = AverageOverDatasets(Column(ds, m.key));
    t += "| " + m.key + " | " + std::to_string(s.queries) + " | " + Fmt("%.0f", s.candidates_mean) + " | " +
         Pct(s.anr) + " | " + Rate(s.recall_at_1) + " | " + Rate(s.top1) + " | " + Rate(s.top5) + " | " +
         Rate(s.top10) + " | " + Rate(s.place_at_1) + " | " + Rate(s.place_at_5) + " | " +
         (s.pose_count ? Fmt("%.3f", s.pose_err_m_median) + " / " + Fmt("%.3f", s.pose_err_m_p90) : "-") + " | " +
         (s.pose_count ? Fmt("%.2f", s.pose_err_deg_median) + " / " + Fmt("%.2f", s.pose_err_deg_p90) : "-") +
         " | " + Fmt("%.1f", s.ms_per_query) + " |\n";
  }
  return t;
}

std::string PerDatasetTable(const std::vector<MethodSpec>& specs, const std::vector<DatasetResults>& ds,
                            const std::vector<std::string>& keys, const std::string& what,
                            double (*get)(const RetrievalSummary&), const char* fmt) {
  std::string t = "| dataset | maps | queries |";
  std::string sep = "|---|---|---|";
  for (const std::string& k : keys) t += " " + k + " |", sep += "---|";
  t += "\n" + sep + "\n";
  for (const DatasetResults& d : ds) {
    t += "| " + d.name + " | " + std::to_string(d.maps) + " | " + std::to_string(d.queries) + " |";
    for (const std::string& k : keys) {
      auto it = d.methods.find(k);
      t += " " + (it == d.methods.end() ? std::string("-") : Fmt(fmt, get(it->second))) + " |";
    }
    t += "\n";
  }
  t += "| **mean** | | |";
  for (const std::string& k : keys) t += " **" + Fmt(fmt, get(AverageOverDatasets(Column(ds, k)))) + "** |";
  (void)specs;
  (void)what;
  return t + "\n";
}

std::string ReportMd(const std::vector<MethodSpec>& specs, const std::vector<DatasetResults>& ds,
                     const RunInfo& info) {
  std::string r = "# lmd-eval retrieval report\n\n";
  r += "Command: `" + info.command + "`  \nDate: " + info.date + "  \nMachine: " + info.machine +
       "  \nSeed: " + std::to_string(info.seed) + ", threads: " + std::to_string(info.threads) +
       ", wall time: " + Fmt("%.0f", info.seconds) + " s\n\n";
  r += "Protocol (DESIGN.md §4): local maps of 5 m every 1 m, each in its own frame; candidates = maps starting "
       "more than 10 m of travel away; one simulated change (seeded) in every query, described after the change; "
       "every query is ranked against all its candidates. *Paper's scoring*: the relevant map = the candidate with "
       "the smallest mean point distance (< 0.5 m); ANR = mean rank / candidates (ties count half), top-X % = the "
       "relevant map within the best X % of the candidates (at least rank 1). *Place recall@k*: a hit is right when "
       "at least 50 % of the query's points lie within 0.3 m of its points (global frame); queries with no such "
       "candidate are left out. *Pose error*: the metric pose of a right top hit (query own frame in the db map's "
       "own frame) against the logs' global poses. Overall rows average the datasets with equal weight.\n\n";
  r += "## Overall (mean over datasets)\n\n";
  r += OverallTable(specs, ds, {"paper", "best"});
  r += "\n## Table I (paper): ANR (%) per descriptor setting (LMD, CoG planner)\n\n";
  std::vector<std::string> descs;
  for (const MethodSpec& m : specs) {
    if (m.group == "descriptor") descs.push_back(m.key);
  }
  if (!descs.empty()) {
    r += "| setting |";
    std::string sep = "|---|";
    for (const MethodSpec& m : specs) {
      if (m.group == "descriptor") r += " " + m.label + " |", sep += "---|";
    }
    r += "\n" + sep + "\n| ANR % |";
    for (const std::string& k : descs) r += " " + Pct(AverageOverDatasets(Column(ds, k)).anr) + " |";
    r += "\n| top-10 % |";
    for (const std::string& k : descs) r += " " + Rate(AverageOverDatasets(Column(ds, k)).top10) + " |";
    r += "\n| place@1 |";
    for (const std::string& k : descs) r += " " + Rate(AverageOverDatasets(Column(ds, k)).place_at_1) + " |";
    r += "\n\nPer dataset (ANR %):\n\n";
    r += PerDatasetTable(specs, ds, descs, "anr", [](const RetrievalSummary& s) { return s.anr; }, "%.1f");
  }
  std::vector<std::string> main_keys;
  for (const MethodSpec& m : specs) {
    if (m.group == "paper" || m.group == "best") main_keys.push_back(m.key);
  }
  r += "\n## Table II (paper): top-10 % and top-5 % recognition rate per method (count / queries)\n\n";
  r += "| method | top-10 % | top-5 % | top-1 % |\n|---|---|---|---|\n";
  for (const std::string& k : main_keys) {
    const RetrievalSummary s = AverageOverDatasets(Column(ds, k));
    r += "| " + k + " | " + Rate(s.top10) + " (" + std::to_string(s.top10_count) + "/" + std::to_string(s.queries) +
         ") | " + Rate(s.top5) + " (" + std::to_string(s.top5_count) + "/" + std::to_string(s.queries) + ") | " +
         Rate(s.top1) + " (" + std::to_string(s.top1_count) + "/" + std::to_string(s.queries) + ") |\n";
  }
  r += "\nPaper: top-10 % 0.44 (LMD+CoG), 0.45 (LMD+CoR), 0.25 (BoW), 0.54 (LMD+CoR stationary); ANR about 25 %.\n";
  r += "\n### ANR (%) per dataset\n\n";
  r += PerDatasetTable(specs, ds, main_keys, "anr", [](const RetrievalSummary& s) { return s.anr; }, "%.1f");
  r += "\n![ANR per dataset](anr.svg)\n";
  r += "\n### top-10 % per dataset\n\n";
  r += PerDatasetTable(specs, ds, main_keys, "top10", [](const RetrievalSummary& s) { return s.top10; }, "%.2f");
  r += "\n## Place recall\n\n### place recall@1 per dataset\n\n";
  r += PerDatasetTable(specs, ds, main_keys, "p1", [](const RetrievalSummary& s) { return s.place_at_1; }, "%.2f");
  r += "\n### place recall@5 per dataset\n\n";
  r += PerDatasetTable(specs, ds, main_keys, "p5", [](const RetrievalSummary& s) { return s.place_at_5; }, "%.2f");
  r += "\n![place recall@1 per dataset](place_recall.svg)\n";
  r += "\n### pose error of right top hits (median m / median deg) per dataset\n\n";
  r += PerDatasetTable(specs, ds, main_keys, "pe", [](const RetrievalSummary& s) { return s.pose_err_m_median; },
                       "%.3f");
  r += "\n";
  r += PerDatasetTable(specs, ds, main_keys, "pd", [](const RetrievalSummary& s) { return s.pose_err_deg_median; },
                       "%.2f");

  // Ablations.
  std::vector<std::string> abl;
  for (const MethodSpec& m : specs) {
    if (m.group == "ablation") abl.push_back(m.key);
  }
  if (!abl.empty()) {
    r += "\n## Ablations of best (each row changes one option of best)\n\n";
    r += "| row | change | ANR % | top-1 % | top-10 % | place@1 | place@5 | pose m | pose deg | ms/query | "
         "change success@1 / @10 |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const MethodSpec& m : specs) {
      if (m.group != "best" && m.group != "ablation") continue;
      const RetrievalSummary s = AverageOverDatasets(Column(ds, m.key));
      r += "| " + m.key + " | " + (m.group == "best" ? std::string("(all options)") : m.note) + " | " + Pct(s.anr) +
           " | " + Rate(s.top1) + " | " + Rate(s.top10) + " | " + Rate(s.place_at_1) + " | " + Rate(s.place_at_5) +
           " | " + Fmt("%.3f", s.pose_err_m_median) + " | " + Fmt("%.2f", s.pose_err_deg_median) + " | " +
           Fmt("%.1f", s.ms_per_query) + " | " + MethodChangeCell(ds, m.key) + " |\n";
    }
    r += "\nplace@1 per dataset:\n\n";
    std::vector<std::string> keys = {"best"};
    keys.insert(keys.end(), abl.begin(), abl.end());
    r += PerDatasetTable(specs, ds, keys, "p1", [](const RetrievalSummary& s) { return s.place_at_1; }, "%.2f");
  }

  // Change detection.
  const ChangeResult all = AverageChange(ds);
  if (!all.curves.empty()) {
    r += "\n## Change detection (method: " + ds[0].change_method + ")\n\n";
    r += "A task (one query with its simulated change) succeeds at rank k when one of the top k change masks is "
         "against a map that shows the query's place and lies within 0.5 m of a truly changed point. False alarm "
         "rate: the share of the top-10 masks (default threshold T = 1.5) that are not such a mask.\n\n";
    r += "| dataset | tasks | success@1 | success@10 | false alarms | masks (top 10) |\n|---|---|---|---|---|---|\n";
    for (const DatasetResults& d : ds) {
      if (d.change_method.empty()) continue;
      r += "| " + d.name + " | " + std::to_string(d.change.tasks) + " | " + Rate(d.change.success_at_1) + " | " +
           Rate(d.change.success_at_10) + " | " + Rate(d.change.false_alarm_rate) + " | " +
           Fmt("%.1f", d.change.masks_mean) + " |\n";
    }
    r += "| **mean** | " + std::to_string(all.tasks) + " | **" + Rate(all.success_at_1) + "** | **" +
         Rate(all.success_at_10) + "** | " + Rate(all.false_alarm_rate) + " | " + Fmt("%.1f", all.masks_mean) + " |\n";
    r += "\nSuccess rate at k (mean over datasets) per threshold T_NN-d:\n\n| T |";
    std::string sep = "|---|";
    for (size_t k : all.ks) r += " k=" + std::to_string(k) + " |", sep += "---|";
    r += "\n" + sep + "\n";
    for (const auto& [t, curve] : all.curves) {
      r += "| " + Fmt("%g", t) + " |";
      for (double v : curve) r += " " + Rate(v) + " |";
      r += "\n";
    }
    r += "\n![change detection, all datasets](change_overall.svg)\n";
    for (const DatasetResults& d : ds) {
      if (!d.change_method.empty()) r += "![change detection " + d.name + "](change_" + d.name + ".svg)\n";
    }
  }
  return r;
}

// ---------------------------------------------------------------------------
// Plots.

const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                          "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

// Grouped bars: groups (datasets) x series (methods).
std::string BarChart(const std::string& title, const std::string& ylabel, const std::vector<std::string>& groups,
                     const std::vector<std::string>& series, const std::vector<std::vector<double>>& values,
                     double ymax) {
  const double gw = static_cast<double>(series.size()) + 1.5;  // world units per group
  const double w = gw * static_cast<double>(groups.size());
  SvgWriter svg(-0.12 * w, -0.25 * ymax, w + 0.02 * w, 1.18 * ymax, 900);
  SvgStyle axis;
  svg.Line({0, 0}, {w, 0}, axis);
  svg.Line({0, 0}, {0, ymax}, axis);
  SvgStyle grid;
  grid.stroke = "#cccccc", grid.dash = "3 3";
  for (int i = 1; i <= 4; ++i) {
    const double y = ymax * i / 4;
    svg.Line({0, y}, {w, y}, grid);
    svg.Text({-0.01 * w, y}, Fmt(ymax >= 10 ? "%.0f" : "%.2f", y), 11, "black", "end");
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    for (size_t s = 0; s < series.size(); ++s) {
      const double x0 = g * gw + 0.75 + s;
      const double v = std::clamp(values[g][s], 0.0, ymax);
      SvgStyle bar;
      bar.stroke = "none", bar.fill = kColours[s % 10];
      svg.Rect(x0, 0, x0 + 0.9, v, bar);
    }
    svg.Text({g * gw + gw / 2, -0.07 * ymax}, groups[g], 12, "black", "middle");
  }
  svg.TextPx(svg.width_px() / 2, 18, title, 15, "black", "middle");
  svg.TextPx(8, 18, ylabel, 12);
  for (size_t s = 0; s < series.size(); ++s) {
    const double x = 60 + 120.0 * static_cast<double>(s);
    svg.Raw("<rect x=\"" + Fmt("%.1f", x) + "\" y=\"" + Fmt("%.1f", svg.height_px() - 22) +
            "\" width=\"12\" height=\"12\" fill=\"" + kColours[s % 10] + "\"/>");
    svg.TextPx(x + 16, svg.height_px() - 11, series[s], 11);
  }
  return svg.ToString();
}

// Curves over log10(k).
std::string CurveChart(const std::string& title, const std::vector<size_t>& ks,
                       const std::map<double, std::vector<double>>& curves) {
  if (ks.empty()) return "";
  const double xmax = std::log10(static_cast<double>(ks.back()));
  SvgWriter svg(-0.15 * xmax, -0.2, xmax * 1.3, 1.12, 700);
  SvgStyle axis;
  svg.Line({0, 0}, {xmax, 0}, axis);
  svg.Line({0, 0}, {0, 1}, axis);
  SvgStyle grid;
  grid.stroke = "#cccccc", grid.dash = "3 3";
  for (int i = 1; i <= 4; ++i) {
    svg.Line({0, i / 4.0}, {xmax, i / 4.0}, grid);
    svg.Text({-0.02 * xmax, i / 4.0}, Fmt("%.2f", i / 4.0), 11, "black", "end");
  }
  for (size_t k : ks) {
    const double x = std::log10(static_cast<double>(k));
    svg.Line({x, 0}, {x, -0.02}, axis);
    svg.Text({x, -0.07}, std::to_string(k), 11, "black", "middle");
  }
  svg.Text({xmax / 2, -0.15}, "k (change masks, log scale)", 12, "black", "middle");
  size_t c = 0;
  for (const auto& [t, curve] : curves) {
    std::vector<Point2> pts;
    for (size_t i = 0; i < ks.size() && i < curve.size(); ++i) {
      pts.push_back({std::log10(static_cast<double>(ks[i])), curve[i]});
    }
    SvgStyle line;
    line.stroke = kColours[c % 10], line.stroke_width_px = t == kDefaultChangeThreshold ? 3 : 1.5;
    if (t == kDefaultChangeThreshold) line.dash = "6 3";
    svg.Polyline(pts, line);
    svg.Text({xmax * 1.03, 1.0 - 0.09 * static_cast<double>(c)}, "T = " + Fmt("%g", t), 11, kColours[c % 10]);
    ++c;
  }
  svg.TextPx(svg.width_px() / 2, 18, title, 15, "black", "middle");
  return svg.ToString();
}

bool WriteFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  return static_cast<bool>(f);
}

}  // namespace

bool WriteResults(const std::string& dir, const std::vector<MethodSpec>& specs,
                  const std::vector<DatasetResults>& ds, const RunInfo& info) {
  namespace fs = std::filesystem;
  bool ok = WriteFile((fs::path(dir) / "results.json").string(), ResultsJson(specs, ds, info));
  ok = ok && WriteFile((fs::path(dir) / "report.md").string(), ReportMd(specs, ds, info));
  std::vector<std::string> keys, groups;
  for (const MethodSpec& m : specs) {
    if (m.group == "paper" || m.group == "best") keys.push_back(m.key);
  }
  for (const DatasetResults& d : ds) groups.push_back(d.name);
  groups.push_back("mean");
  std::vector<std::vector<double>> anr(groups.size()), p1(groups.size());
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const std::string& k : keys) {
      RetrievalSummary s;
      if (g + 1 < groups.size()) {
        auto it = ds[g].methods.find(k);
        if (it != ds[g].methods.end()) s = it->second;
      } else {
        s = AverageOverDatasets(Column(ds, k));
      }
      anr[g].push_back(s.anr), p1[g].push_back(s.place_at_1);
    }
  }
  double anr_max = 10;
  for (const auto& row : anr) {
    for (double v : row) anr_max = std::max(anr_max, v);
  }
  anr_max = 10 * std::ceil(anr_max / 10);
  ok = ok && WriteFile((fs::path(dir) / "anr.svg").string(),
                       BarChart("ANR per dataset and method (lower is better; paper Fig. 6)", "ANR %", groups, keys,
                                anr, anr_max));
  ok = ok && WriteFile((fs::path(dir) / "place_recall.svg").string(),
                       BarChart("place recall@1 per dataset and method", "place@1", groups, keys, p1, 1.0));
  const ChangeResult all = AverageChange(ds);
  if (!all.curves.empty()) {
    ok = ok && WriteFile((fs::path(dir) / "change_overall.svg").string(),
                         CurveChart("change detection success over k, mean of datasets (paper Fig. 7)", all.ks,
                                    all.curves));
    for (const DatasetResults& d : ds) {
      if (d.change_method.empty()) continue;
      ok = ok && WriteFile((fs::path(dir) / ("change_" + d.name + ".svg")).string(),
                           CurveChart("change detection success over k: " + d.name, d.change.ks, d.change.curves));
    }
  }
  return ok;
}

}  // namespace lmd::eval
