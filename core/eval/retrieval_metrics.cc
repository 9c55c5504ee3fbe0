#include "core/eval/retrieval_metrics.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/pose_ops.h"

namespace lmd {

double RankOfTarget(const std::vector<double>& scores, size_t target) {
  if (target >= scores.size()) return 0.0;
  const double s = scores[target];
  size_t higher = 0, tied = 0;
  for (size_t i = 0; i < scores.size(); ++i) {
    if (i == target) continue;
    if (scores[i] > s) {
      ++higher;
    } else if (scores[i] == s) {
      ++tied;
    }
  }
  return 1.0 + static_cast<double>(higher) + 0.5 * static_cast<double>(tied);
}

bool WithinTopPercent(double rank, size_t candidates, double percent) {
  const double limit = std::max(1.0, percent / 100.0 * static_cast<double>(candidates));
  return rank <= limit + 1e-9;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

RetrievalSummary Summarize(const std::vector<QueryOutcome>& outcomes) {
  RetrievalSummary s;
  s.queries = outcomes.size();
  if (outcomes.empty()) return s;
  double cand = 0, anr = 0, ms = 0;
  size_t r1 = 0, p1 = 0, p5 = 0;
  std::vector<double> em, ed;
  for (const QueryOutcome& o : outcomes) {
    cand += static_cast<double>(o.candidates);
    anr += o.candidates ? o.rank / static_cast<double>(o.candidates) : 1.0;
    ms += o.ms;
    if (o.rank <= 1.0) ++r1;
    if (WithinTopPercent(o.rank, o.candidates, 1)) ++s.top1_count;
    if (WithinTopPercent(o.rank, o.candidates, 5)) ++s.top5_count;
    if (WithinTopPercent(o.rank, o.candidates, 10)) ++s.top10_count;
    if (o.place_counted) {
      ++s.place_queries;
      if (o.first_place_hit == 0) ++p1;
      if (o.first_place_hit >= 0 && o.first_place_hit < 5) ++p5;
    }
    if (o.has_pose) em.push_back(o.pose_err_m), ed.push_back(o.pose_err_deg);
  }
  const double n = static_cast<double>(outcomes.size());
  s.candidates_mean = cand / n;
  s.anr = 100.0 * anr / n;
  s.recall_at_1 = r1 / n;
  s.top1 = s.top1_count / n, s.top5 = s.top5_count / n, s.top10 = s.top10_count / n;
  if (s.place_queries) {
    s.place_at_1 = static_cast<double>(p1) / s.place_queries;
    s.place_at_5 = static_cast<double>(p5) / s.place_queries;
  }
  s.pose_count = em.size();
  s.pose_err_m_median = Quantile(em, 0.5), s.pose_err_m_p90 = Quantile(em, 0.9);
  s.pose_err_deg_median = Quantile(ed, 0.5), s.pose_err_deg_p90 = Quantile(ed, 0.9);
  s.ms_per_query = ms / n;
  return s;
}

RetrievalSummary AverageOverDatasets(const std::vector<RetrievalSummary>& d) {
  RetrievalSummary s;
  if (d.empty()) return s;
  const double n = static_cast<double>(d.size());
  size_t with_pose = 0;
  for (const RetrievalSummary& r : d) {
    s.queries += r.queries;
    s.top1_count += r.top1_count, s.top5_count += r.top5_count, s.top10_count += r.top10_count;
    s.place_queries += r.place_queries;
    s.pose_count += r.pose_count;
    s.candidates_mean += r.candidates_mean / n;
    s.anr += r.anr / n;
    s.recall_at_1 += r.recall_at_1 / n;
    s.top1 += r.top1 / n, s.top5 += r.top5 / n, s.top10 += r.top10 / n;
    s.place_at_1 += r.place_at_1 / n, s.place_at_5 += r.place_at_5 / n;
    s.ms_per_query += r.ms_per_query / n;
    if (r.pose_count) {
      ++with_pose;
      s.pose_err_m_median += r.pose_err_m_median, s.pose_err_m_p90 += r.pose_err_m_p90;
      s.pose_err_deg_median += r.pose_err_deg_median, s.pose_err_deg_p90 += r.pose_err_deg_p90;
    }
  }
  if (with_pose) {
    const double w = static_cast<double>(with_pose);
    s.pose_err_m_median /= w, s.pose_err_m_p90 /= w, s.pose_err_deg_median /= w, s.pose_err_deg_p90 /= w;
  }
  return s;
}

void PoseError(const Pose2& estimate, const Pose2& truth, double* err_m, double* err_deg) {
  *err_m = std::hypot(estimate.x - truth.x, estimate.y - truth.y);
  *err_deg = std::abs(NormalizeAngle(estimate.theta - truth.theta)) * 180.0 / M_PI;
}

std::vector<double> SuccessCurve(const std::vector<size_t>& first_success, const std::vector<size_t>& ks) {
  std::vector<double> rates(ks.size(), 0.0);
  if (first_success.empty()) return rates;
  for (size_t i = 0; i < ks.size(); ++i) {
    size_t ok = 0;
    for (size_t f : first_success) ok += (f > 0 && f <= ks[i]);
    rates[i] = static_cast<double>(ok) / static_cast<double>(first_success.size());
  }
  return rates;
}

bool MaskHitsChange(const std::vector<Point2>& mask_points, const std::vector<Point2>& changed_points,
                    double radius_m) {
  const double r2 = radius_m * radius_m;
  for (const Point2& m : mask_points) {
    for (const Point2& c : changed_points) {
      const double dx = m.x - c.x, dy = m.y - c.y;
      if (dx * dx + dy * dy <= r2) return true;
    }
  }
  return false;
}

std::vector<size_t> LogSteps(size_t max_k) {
  std::vector<size_t> ks;
  const size_t mult[3] = {1, 2, 5};
  for (size_t decade = 1;; decade *= 10) {
    for (size_t m : mult) {
      ks.push_back(m * decade);
      if (m * decade >= max_k) return ks;
    }
  }
}

}  // namespace lmd
