// lmd-eval truth-audit: how much of the pose error lmd-eval reports is the
// log's ground truth, not the scan matcher. For a query map q and two maps j
// and m that show its place (and that fit each other), lmdd's matcher (the
// scan match from near the log's relative pose, then the refinement that
// gives a served hit its pose) poses q in j, q in m and j in m. Each is compared
// with the log's relative pose, as lmd-eval served scores a hit. The three
// also close a loop in which the log's poses cancel: q in m against (j in m)
// after (q in j). If the matches' errors are independent, the loop's error
// is about sqrt(3) times one match's own error; what a match's error against
// the log has beyond that is the log's relative pose error.
//
// It also asks, of each map with at least three maps of its place, whether
// they agree on moving it: each poses the map within +-3 m of the log's
// pose, and when at least three agree (within 0.1 m and 0.5 deg of their
// median) on a pose off the log's by more than a sure answer may be (0.2 m
// or 1 deg), the map's own log pose is likely wrong (or its local map
// distorted). --list prints those maps.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/eval/answer_scoring.h"
#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/stored_log.h"
#include "core/eval/retrieval_metrics.h"
#include "core/eval/truth_audit.h"
#include "core/localmap/pose_ops.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

struct AuditCounts {
  std::string name;
  size_t loops = 0;
  size_t log_off = 0;  // loops that close, with a match off the log's pose as far as a sure answer may be
  std::vector<double> truth_cm, truth_deg;  // each match against the log's relative pose
  std::vector<double> loop_cm, loop_deg;    // each loop's closing error
  size_t judged = 0;  // maps on whose pose at least three maps of their place agree
  size_t moved = 0;   // ... and put it off the log's by more than a sure answer may be
};

// A loop this tight says the matches agree with each other (and a match off
// the log's pose by more than a sure answer may be, kSurePoseM, that the
// log is off).
constexpr double kClosedCm = 5.0, kClosedDeg = 0.25;

// Map `a` (prepared as `query`) posed in `b` by lmdd's matcher and
// refinement, from near the log's pose (core/eval/truth_audit.h). False when
// the match is no fix.
bool MatchFromTruth(const Dataset& d, const StoredLog& stored, const LocalizeOptions& options, const LocalQuery& query,
                    size_t a, size_t b, Pose2* pose) {
  const std::shared_ptr<const PreparedMap> db = stored.collection.Prepared(b);
  if (!db) return false;
  const std::optional<Pose2> m = MatchNearLogPose(query, *db, d.TruePose(a, b), options);
  if (m) *pose = *m;
  return m.has_value();
}

void AddError(const Pose2& estimate, const Pose2& truth, std::vector<double>* cm, std::vector<double>* deg) {
  double err_m = 0, err_deg = 0;
  PoseError(estimate, truth, &err_m, &err_deg);
  cm->push_back(100 * err_m), deg->push_back(err_deg);
}

AuditCounts Audit(const Dataset& d, const LocalizeOptions& options, size_t every, bool list) {
  AuditCounts counts;
  counts.name = d.name;
  const std::unique_ptr<StoredLog> stored = StoreLog(d, options, false);
  ProgressBar bar(d.name + ": loops of three matches", d.queries.size());
  for (size_t k = 0; k < d.queries.size(); ++k) {
    bar.Add();
    const EvalQuery& q = d.queries[k];
    if (k % every != 0) continue;
    const LocalQuery query = PrepareLocalQuery(d.maps[q.map], options, &stored->places[q.map]);
    std::vector<PlaceMap> place;
    std::vector<std::shared_ptr<const PreparedMap>> held;  // keeps `place`'s maps alive
    for (size_t j : q.places) {
      held.push_back(stored->collection.Prepared(j));
      if (held.back()) place.push_back({held.back().get(), d.TruePose(q.map, j)});
    }
    const std::optional<PlaceMove> moved = MoveByItsPlace(query, place, options);
    if (moved) {
      ++counts.judged;
      const Pose2& m = moved->move;
      if (std::hypot(m.x, m.y) > kSurePoseM || std::abs(m.theta) * 180 / M_PI > kSurePoseDeg) {
        ++counts.moved;
        if (list) {
          std::fprintf(stderr, "%s: %s moved %.2f m %.2f deg by %zu of the %zu maps of its place\n", d.name.c_str(),
                       d.maps[q.map].id.c_str(), std::hypot(m.x, m.y), m.theta * 180 / M_PI, moved->agreeing,
                       q.places.size());
        }
      }
    }
    // The first two maps of q's place that the matcher fits to each other.
    bool closed = false;
    for (size_t jx = 0; jx < q.places.size() && !closed; ++jx) {
      const size_t j = q.places[jx];
      Pose2 qj_pose;
      if (!MatchFromTruth(d, *stored, options, query, q.map, j, &qj_pose)) continue;
      const LocalQuery j_query = PrepareLocalQuery(d.maps[j], options, &stored->places[j]);
      for (size_t mx = jx + 1; mx < q.places.size() && !closed; ++mx) {
        const size_t m = q.places[mx];
        Pose2 qm_pose, jm_pose;
        if (!MatchFromTruth(d, *stored, options, j_query, j, m, &jm_pose) ||
            !MatchFromTruth(d, *stored, options, query, q.map, m, &qm_pose)) {
          continue;
        }
        closed = true;
        ++counts.loops;
        AddError(qj_pose, d.TruePose(q.map, j), &counts.truth_cm, &counts.truth_deg);
        AddError(qm_pose, d.TruePose(q.map, m), &counts.truth_cm, &counts.truth_deg);
        AddError(jm_pose, d.TruePose(j, m), &counts.truth_cm, &counts.truth_deg);
        AddError(Compose(jm_pose, qj_pose), qm_pose, &counts.loop_cm, &counts.loop_deg);
        bool off = false;
        for (size_t i = counts.truth_cm.size() - 3; i < counts.truth_cm.size(); ++i) {
          off |= counts.truth_cm[i] > 100 * kSurePoseM || counts.truth_deg[i] > kSurePoseDeg;
        }
        if (off && counts.loop_cm.back() <= kClosedCm && counts.loop_deg.back() <= kClosedDeg) ++counts.log_off;
      }
    }
  }
  bar.Done();
  return counts;
}

double Median(std::vector<double> v) { return v.empty() ? 0.0 : Quantile(v, 0.5); }

void Print(const AuditCounts& c) {
  const double truth = Median(c.truth_cm), loop = Median(c.loop_cm);
  const double matcher = loop / std::sqrt(3.0);
  std::printf("%-10s %6zu %13.1f %12.2f %12.1f %11.2f %11.1f %12.1f %14zu %8zu %8zu\n", c.name.c_str(), c.loops, truth,
              Median(c.truth_deg), loop, Median(c.loop_deg), matcher,
              std::sqrt(std::max(0.0, truth * truth - matcher * matcher)), c.log_off, c.judged, c.moved);
}

}  // namespace

int RunTruthAudit(int argc, char** argv) {
  Flags args(WithSensorFlags({"log", "every"}), {"list"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval truth-audit: %s\n", args.error().c_str());
    return 2;
  }
  size_t every = 0;
  if (!ParseEvery(args, "truth-audit", &every)) return 2;
  const LocalizeOptions options;  // lmdd's defaults
  std::vector<AuditCounts> all;
  const int read = ForEachServedLog(args, "truth-audit", [&](const Dataset& d) {
    all.push_back(Audit(d, options, every, args.Has("list")));
  });
  if (read != 0) return read;
  std::printf("medians; a match: lmdd's pose of one map in another against the log's; a loop: three matches closed\n");
  std::printf("%-10s %6s %13s %12s %12s %11s %11s %12s %14s %8s %8s\n", "log", "loops", "match cm", "match deg",
              "loop cm", "loop deg", "matcher cm", "log's cm", "log off, 0.2m", "judged", "moved");
  AuditCounts total;
  total.name = "all";
  for (const AuditCounts& c : all) {
    Print(c);
    total.loops += c.loops, total.log_off += c.log_off, total.judged += c.judged, total.moved += c.moved;
    total.truth_cm.insert(total.truth_cm.end(), c.truth_cm.begin(), c.truth_cm.end());
    total.truth_deg.insert(total.truth_deg.end(), c.truth_deg.begin(), c.truth_deg.end());
    total.loop_cm.insert(total.loop_cm.end(), c.loop_cm.begin(), c.loop_cm.end());
    total.loop_deg.insert(total.loop_deg.end(), c.loop_deg.begin(), c.loop_deg.end());
  }
  Print(total);
  return 0;
}

}  // namespace lmd::eval
