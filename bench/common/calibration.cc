#include "bench/common/calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>

#include "core/render/svg_writer.h"

namespace lmd {

Reliability MeasureReliability(const std::vector<StatedOutcome>& outcomes) {
  Reliability r;
  r.answers = outcomes.size();
  if (outcomes.empty()) return r;
  for (const StatedOutcome& o : outcomes) {
    // A probability outside [0, 1] (none lmdd states) counts at the nearest end; NaN as 0.
    const double p = std::isnan(o.probability) ? 0.0 : std::clamp(o.probability, 0.0, 1.0);
    const int bin = std::min(static_cast<int>(p * kReliabilityBins), kReliabilityBins - 1);
    ++r.count[bin];
    r.mean_probability[bin] += p;
    const double outcome = o.right ? 1.0 : 0.0;
    r.share_right[bin] += outcome;
    r.brier += (p - outcome) * (p - outcome);
  }
  const double n = static_cast<double>(outcomes.size());
  r.brier /= n;
  for (int b = 0; b < kReliabilityBins; ++b) {
    if (r.count[b] == 0) continue;
    r.calibration_error += std::abs(r.mean_probability[b] - r.share_right[b]) / n;
    r.mean_probability[b] /= static_cast<double>(r.count[b]);
    r.share_right[b] /= static_cast<double>(r.count[b]);
  }
  return r;
}

std::string ReliabilitySvg(const std::vector<ReliabilitySeries>& series, const std::string& title) {
  constexpr double kSide = 10.0;  // world units for 1.0
  constexpr double kLegendRow = 0.7;
  // Legends below the axis title, where no line can run through them.
  const double bottom = -2.1 - kLegendRow * static_cast<double>(series.size());
  SvgWriter svg(-1.6, bottom, kSide + 0.4, kSide + 1.6, 560);
  const SvgStyle grid{"#ccc", 0.5, "none", 1.0, "3 3"};
  for (int i = 0; i <= 5; ++i) {
    const double v = i * 0.2 * kSide;
    svg.Line({v, 0}, {v, kSide}, grid);
    svg.Line({0, v}, {kSide, v}, grid);
    char label[8];
    std::snprintf(label, sizeof label, "%.1f", i * 0.2);
    svg.Text({v, -0.55}, label, 11, "#444", "middle");
    svg.Text({-0.2, v - 0.12}, label, 11, "#444", "end");
  }
  svg.Line({0, 0}, {kSide, kSide}, SvgStyle{"#888", 1.0, "none", 1.0, "6 3"});
  svg.Text({kSide / 2, -1.3}, "stated probability of being right", 12, "black", "middle");
  svg.Text({0, kSide + 0.5}, "share right", 12, "black", "start");
  const char* colours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"};
  for (size_t i = 0; i < series.size(); ++i) {
    const Reliability& r = series[i].reliability;
    const std::string colour = colours[i % (sizeof colours / sizeof colours[0])];
    std::vector<Point2> points;
    for (int b = 0; b < kReliabilityBins; ++b) {
      if (r.count[b] > 0) points.push_back({r.mean_probability[b] * kSide, r.share_right[b] * kSide});
    }
    const SvgStyle style{colour, 2.0, "none", 1.0, ""};
    svg.Polyline(points, style);
    for (const Point2& p : points) svg.Circle(p, 3.5, SvgStyle{colour, 1.0, colour, 1.0, ""});
    char legend[160];
    std::snprintf(legend, sizeof legend, "%s: %zu answers, calibration error %.3f", series[i].name.c_str(),
                  r.answers, r.calibration_error);
    const double y = -2.1 - kLegendRow * static_cast<double>(i);
    svg.Line({0.4, y}, {1.2, y}, style);
    svg.Text({1.4, y - 0.15}, legend, 12, "black");
  }
  svg.TextPx(280, 16, title, 14, "black", "middle");
  return svg.ToString();
}

LogisticFit FitLogistic(const std::vector<CalibrationSample>& samples) {
  constexpr double kRidge = 1e-3;
  constexpr int kIterations = 50;
  Eigen::Vector4d w = Eigen::Vector4d::Zero();  // bias, score, margin, sure
  for (int it = 0; it < kIterations && !samples.empty(); ++it) {
    Eigen::Vector4d gradient = kRidge * w;
    Eigen::Matrix4d hessian = kRidge * Eigen::Matrix4d::Identity();
    for (const CalibrationSample& s : samples) {
      const Eigen::Vector4d x(1.0, s.best_score, s.margin, s.sure ? 1.0 : 0.0);
      const double p = 1.0 / (1.0 + std::exp(-std::clamp(w.dot(x), -30.0, 30.0)));
      gradient += (p - (s.right ? 1.0 : 0.0)) * x;
      hessian += p * (1.0 - p) * x * x.transpose();
    }
    const Eigen::Vector4d step = hessian.ldlt().solve(gradient);
    w -= step;
    if (step.norm() < 1e-10) break;
  }
  return LogisticFit{w[0], w[1], w[2], w[3]};
}

}  // namespace lmd
