#include "bench/eval/served_report.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include <fmt/printf.h>

#include "core/render/svg_writer.h"

namespace lmd::eval {
namespace {

constexpr char kCsvHeader[] =
    "log,query,place_counted,first_place_hit,pose_err_m,pose_err_deg,localized,localized_right,"
    "wrong_pose_fits_better,confidence,best_score,rival_score,rival,agreeing,cpu_ms,wall_ms,changed_localized,"
    "first_change_mask,masks,false_masks,changed_best_score,changed_rival_score,changed_cpu_ms,top_hit,site_err_m,"
    "site_err_deg,pose_d2,position_sd_m,heading_sd_deg,vote_lead\n";

struct Group {
  std::string label;
  AnswerSummary still, changed;
  size_t logs = 0;
};

std::vector<Group> Means(const ServedRun& run) {
  std::vector<AnswerSummary> all_s, all_c, tuned_s, tuned_c, held_s, held_c;
  std::string tuned_names, held_names;
  for (const ServedLog& log : run.logs) {
    const bool tuned = std::find(run.tuned_on.begin(), run.tuned_on.end(), log.name) != run.tuned_on.end();
    (tuned ? tuned_s : held_s).push_back(log.still);
    (tuned ? tuned_c : held_c).push_back(log.changed);
    std::string& names = tuned ? tuned_names : held_names;
    names += (names.empty() ? "" : ", ") + log.name;
    all_s.push_back(log.still), all_c.push_back(log.changed);
  }
  std::vector<Group> out;
  if (!held_s.empty()) out.push_back({"mean, held out (" + held_names + ")", MeanOverLogs(held_s), MeanOverLogs(held_c), held_s.size()});
  if (!tuned_s.empty()) out.push_back({"mean, tuned on (" + tuned_names + ")", MeanOverLogs(tuned_s), MeanOverLogs(tuned_c), tuned_s.size()});
  out.push_back({"mean, all logs", MeanOverLogs(all_s), MeanOverLogs(all_c), all_s.size()});
  return out;
}

// `row` of each log's answers to the queries as stored, then of each mean's
// (labelled in bold, followed by `mean_note`).
std::string StillRows(const ServedRun& run, const std::string& mean_note,
                      const std::function<std::string(const std::string&, const AnswerSummary&)>& row) {
  std::string rows;
  for (const ServedLog& log : run.logs) rows += row(log.name, log.still);
  for (const Group& g : Means(run)) rows += row("**" + g.label + "**" + mean_note, g.still);
  return rows;
}

std::string Row(const std::string& label, const std::string& maps, const AnswerSummary& s, const AnswerSummary& c,
                bool with_changes) {
  std::string row = fmt::sprintf(
      "| %s | %s | %zu / %zu | %.3f | %.3f | %.1f / %.1f cm, %.2f / %.2f deg | %.3f | %.4f (%zu wrong, "
      "%zu fit better) | %.1f / %.1f | %.1f / %.1f |",
      label.c_str(), maps.c_str(), s.place_queries, s.queries, s.place_at_1, s.place_at_5, 100 * s.pose_err_m_median,
      100 * s.pose_err_m_p90, s.pose_err_deg_median, s.pose_err_deg_p90, s.localized_share, s.localized_precision,
      s.localized_wrong, s.wrong_pose_fits_better, s.cpu_ms_p50, s.cpu_ms_p99, s.wall_ms_p50, s.wall_ms_p99);
  if (with_changes) {
    row += fmt::sprintf(" %.3f (%zu) | %.3f (%zu of %zu) | %.3f / %.4f | %.1f / %.1f |", c.change_success_at_1,
                        c.change_tasks, c.false_mask_share, c.false_masks, c.masks, c.localized_share,
                        c.localized_precision, c.cpu_ms_p50, c.cpu_ms_p99);
  }
  return row + "\n";
}

std::string Markdown(const ServedRun& run, bool with_changes) {
  std::string md = "# lmd-eval served\n\n";
  md += "Command: `" + run.command + "`  \nDate: " + run.date + "  \n";
  md += fmt::sprintf("Run time %.0f s; lmdd CPU over the run %.0f s.\n\n", run.seconds, run.lmdd_cpu_seconds);
  md += "Every map inserted in its own frame (trajectory, scans; robot = the log), then each sent back as a "
        "query with the maps within 10 m of travel excluded. place@k over the queries with a place among their "
        "candidates (>= 50 % of the query's points within 0.3 m of a hit's); pose error of right top hits "
        "(median / p90); sure = lmdd said `localized`; right = top hit shows the place with its pose within "
        "0.2 m and 1 deg (over all sure answers, queries without a place included; fit better = of the "
        "wrong, near misses (the right place within 0.5 m and 3 deg) whose answered pose explains the query "
        "better than the logs' truth does, where the truth's own error may be the cause); CPU = lmdd's per call "
        "(server_cpu_ms, p50 / p99); wall = the client's, p50 / p99.";
  if (with_changes) {
    md += " Changes: DetectChanges of the map with a simulated change; top mask = share of change tasks "
          "whose first mask finds the change; false = masks returned that find no change of a right hit.";
  }
  md += "\n\n| log | maps | with place / queries | place@1 | place@5 | pose error | sure | sure right | CPU ms | wall ms |";
  if (with_changes) md += " change top mask (tasks) | false masks | changed: sure / right | changed CPU ms |";
  md += "\n|---|---|---|---|---|---|---|---|---|---|";
  if (with_changes) md += "---|---|---|---|";
  md += "\n";
  for (const ServedLog& log : run.logs) md += Row(log.name, std::to_string(log.maps), log.still, log.changed, with_changes);
  for (const Group& g : Means(run)) md += Row("**" + g.label + "**", "", g.still, g.changed, with_changes);
  bool sited = false;
  for (const ServedLog& log : run.logs) sited |= log.still.site_count > 0;
  if (sited) {
    md += "\nSite pose (maps stored at their log poses): the answer's pose in the collection's frame against the "
          "query's log pose, where the top hit shows the place.\n\n| log | answers | site pose error (median / p90) "
          "| deg (median) |\n|---|---|---|---|\n";
    auto site = [](const std::string& label, const AnswerSummary& s) {
      return fmt::sprintf("| %s | %zu | %.1f / %.1f cm | %.2f |\n", label.c_str(), s.site_count,
                          100 * s.site_err_m_median, 100 * s.site_err_m_p90, s.site_err_deg_median);
    };
    md += StillRows(run, "", site);
  }
  md += "\nPose covariance (Localization.pose_covariance): of the answers whose top hit shows the place, the "
        "share whose pose error lies within the covariance's 50 % and 95 % ellipsoids (x, y, theta; chi-square, "
        "3 degrees of freedom), and of the sure ones, within 95 %. Calibrated, they read 0.50 and 0.95.\n\n"
        "| log | answers | within 50 % | within 95 % | sure | sure within 95 % |\n|---|---|---|---|---|---|\n";
  auto covered = [](const std::string& label, const AnswerSummary& s) {
    return fmt::sprintf("| %s | %zu | %.3f | %.3f | %zu | %.3f |\n", label.c_str(), s.covariance_count, s.within_50,
                        s.within_95, s.covariance_sure, s.sure_within_95);
  };
  md += StillRows(run, "", covered);
  md += "\nConfidence (Localization.confidence) against how often the top hit was right (the place, the pose "
        "within 0.2 m and 1 deg), over all answers: calibration error (the answers' share in each tenth of "
        "confidence times the gap between their mean confidence and their share right, summed) and Brier score "
        "(mean squared gap). Lower is better; 0 is perfect.\n\n"
        "| log | answers | calibration error | Brier score |\n|---|---|---|---|\n";
  auto calibration = [](const std::string& label, const AnswerSummary& s) {
    return fmt::sprintf("| %s | %zu | %.3f | %.3f |\n", label.c_str(), s.queries, s.reliability.calibration_error,
                        s.reliability.brier);
  };
  md += StillRows(run, "", calibration);
  md += "\nRight but unsure (the top hit shows the place, its pose within 0.2 m and 1 deg, lmdd not sure), by "
        "the verdict's best rival: none (the best score alone was too low), self (the best map at another pose, "
        "or a rival past the hits returned), same place (a hit whose pose is its true one, to 0.2 m and 1 deg, "
        "yet was taken to disagree), place off (a hit of the place at a wrong pose), elsewhere (a look-alike: "
        "another place, at a wrong pose).\n\n"
        "| log | right but unsure | none | self | same place | place off | elsewhere |\n"
        "|---|---|---|---|---|---|---|\n";
  auto rivals = [](const std::string& label, const AnswerSummary& s) {
    return fmt::sprintf("| %s | %zu | %zu | %zu | %zu | %zu | %zu |\n", label.c_str(), s.unsure_right,
                        s.unsure_right_rival[0], s.unsure_right_rival[1], s.unsure_right_rival[2],
                        s.unsure_right_rival[3], s.unsure_right_rival[4]);
  };
  md += StillRows(run, " (sum)", rivals);
  return md;
}

std::string Json(const ServedRun& run, bool with_changes) {
  std::string j = "{\n  \"command\": \"" + run.command + "\",\n  \"date\": \"" + run.date + "\",\n  \"tuned_on\": [";
  for (size_t i = 0; i < run.tuned_on.size(); ++i) j += (i ? ", \"" : "\"") + run.tuned_on[i] + "\"";
  j += "],\n  \"logs\": [\n";
  for (size_t i = 0; i < run.logs.size(); ++i) {
    const ServedLog& log = run.logs[i];
    j += "    {\"name\": \"" + log.name + "\", \"maps\": " + std::to_string(log.maps) + ", \"still\": " +
         SummaryJson(log.still);
    if (with_changes) j += ", \"changed\": " + SummaryJson(log.changed);
    j += i + 1 < run.logs.size() ? "},\n" : "}\n";
  }
  j += "  ],\n  \"means\": [\n";
  const std::vector<Group> means = Means(run);
  for (size_t i = 0; i < means.size(); ++i) {
    j += "    {\"label\": \"" + means[i].label + "\", \"still\": " + SummaryJson(means[i].still);
    if (with_changes) j += ", \"changed\": " + SummaryJson(means[i].changed);
    j += i + 1 < means.size() ? "},\n" : "}\n";
  }
  return j + "  ]\n}\n";
}

// Bars per log: place@1, share of sure answers, precision of sure answers.
std::string Svg(const ServedRun& run) {
  const size_t n = run.logs.size();
  // The writer scales both axes alike: a value of 1 is `height` world units,
  // a third of the plot's width.
  const double group_w = 3.6, width = std::max<double>(1.0, n) * group_w, height = width / 3;
  const double line = height / 14;  // one text line below the axis
  SvgWriter svg(-1.2, -2.6 * line, width + 0.4, height * 1.12, 960);
  const SvgStyle axis{"#444", 1.0, "none", 1.0, ""};
  svg.Line({0, 0}, {width, 0}, axis);
  for (double y : {0.0, 0.25, 0.5, 0.75, 0.9, 1.0}) {
    svg.Line({0, y * height}, {width, y * height}, SvgStyle{"#bbb", 0.5, "none", 1.0, "3 3"});
    char label[16];
    std::snprintf(label, sizeof label, "%.2g", y);
    svg.Text({-0.15, y * height - 0.1 * line}, label, 11, "#444", "end");
  }
  const char* colours[3] = {"#1f77b4", "#ff7f0e", "#2ca02c"};
  const char* names[3] = {"place@1", "sure share", "sure right"};
  for (size_t i = 0; i < n; ++i) {
    const AnswerSummary& s = run.logs[i].still;
    const double values[3] = {s.place_at_1, s.localized_share, s.localized_precision};
    for (int b = 0; b < 3; ++b) {
      const double x0 = i * group_w + 0.3 + b * 1.0;
      svg.Rect(x0, 0, x0 + 0.9, values[b] * height, SvgStyle{"none", 0, colours[b], 1.0, ""});
    }
    svg.Text({i * group_w + 1.8, -1.0 * line}, run.logs[i].name, 13, "black", "middle");
  }
  for (int b = 0; b < 3; ++b) {
    svg.Rect(b * 3.2, -2.3 * line, b * 3.2 + 0.3, -1.8 * line, SvgStyle{"none", 0, colours[b], 1.0, ""});
    svg.Text({b * 3.2 + 0.45, -2.3 * line}, names[b], 12);
  }
  svg.TextPx(480, 16, "lmd-eval served: per log", 14, "black", "middle");
  return svg.ToString();
}

// The confidence's reliability diagram: the held-out and the tuning logs'
// answers, each pooled.
std::string CalibrationSvg(const ServedRun& run) {
  std::vector<ReliabilitySeries> series;
  for (const Group& g : Means(run)) {
    if (g.label == "mean, all logs") continue;
    const bool held_out = g.label.rfind("mean, held out", 0) == 0;
    series.push_back({held_out ? "held-out logs" : "tuning logs", g.still.reliability});
  }
  return ReliabilitySvg(series, "lmd-eval served: is the confidence calibrated?");
}

}  // namespace

Status WriteServedReport(const std::string& dir, const ServedRun& run, bool with_changes) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  auto write = [&](const std::string& name, const std::string& text) -> Status {
    std::ofstream out(dir + "/" + name);
    out << text;
    return out ? Status::Ok() : Status::IoError("cannot write " + dir + "/" + name);
  };
  std::string csv = kCsvHeader;
  for (const ServedLog& log : run.logs) csv += log.query_lines;
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"results.json", Json(run, with_changes)},
                                   {"report.md", Markdown(run, with_changes)},
                                   {"queries.csv", csv},
                                   {"served.svg", Svg(run)},
                                   {"calibration.svg", CalibrationSvg(run)}}) {
    Status s = write(name, text);
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace lmd::eval
