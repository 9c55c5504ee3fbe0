// lmd-eval retrieval: the paper's experiment on real laser logs (DESIGN.md §4)
// and the product's pipeline, scored both the paper's way (one relevant map
// per query: ANR, recall@1, top-X %) and by place recall and pose error.
//
// Per dataset: local maps, ground truth, one simulated change per query
// (seeded). The paper's methods score every query against ALL its valid
// candidates (exact ranks, no index shortcuts): the LMD kernel
// (core/index/pyramid_kernel.h, the code the index scores with) or BoW;
// descriptors are computed once per (map, planner, descriptor setting) and
// shared. `best` and its ablations are the localisation pipeline lmdd serves
// (core/localize) over the dataset's maps held in memory, each query with
// its candidates only; they are also scored by their verdicts, change masks
// and CPU (answer_scoring.h).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <sstream>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <time.h>

#include <unistd.h>

#include "bench/eval/answer_scoring.h"
#include "bench/common/flags.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/retrieval.h"
#include "core/align/relative_pose.h"
#include "core/change/change_detector.h"
#include "core/describe/describer.h"
#include "core/index/pyramid_kernel.h"
#include "core/localize/localizer.h"
#include "core/localize/memory_collection.h"
#include "core/util/progress_bar.h"

namespace lmd::eval {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// ---------------------------------------------------------------------------
// Methods.

MethodSpec PaperMethod(const std::string& key, const std::string& label, Planner planner, Method method) {
  MethodSpec m;
  m.key = key, m.label = label, m.group = "paper", m.planner = planner, m.method = method;
  return m;
}

// The product: the localisation pipeline with the served defaults
// (core/localize; the options lmdd uses, server/indexing.h).
MethodSpec BestMethod() {
  MethodSpec m;
  m.key = "best", m.label = "best (the served pipeline)", m.group = "best";
  m.pipeline = true;
  return m;
}

std::vector<MethodSpec> DefaultMethods(bool ablations) {
  std::vector<MethodSpec> v;
  v.push_back(PaperMethod("bow", "BoW", Planner::kCoG, Method::kBow));
  MethodSpec cog = PaperMethod("lmd_cog", "LMD+CoG", Planner::kCoG, Method::kLmd);
  cog.change_eval = true;  // the paper's change detector, on the paper's method
  v.push_back(cog);
  v.push_back(PaperMethod("lmd_cor", "LMD+CoR", Planner::kCoR, Method::kLmd));
  MethodSpec st = PaperMethod("lmd_cor_stationary", "LMD+CoR stationary", Planner::kCoR, Method::kLmd);
  st.stationary = true;
  v.push_back(st);
  for (int s = 1; s <= 8; ++s) {
    const DescriptorSetting ds = PaperDescriptorSetting(s);
    MethodSpec d = PaperMethod("desc" + std::to_string(s), "", Planner::kCoG, Method::kLmd);
    char label[64];
    std::snprintf(label, sizeof label, "#%d (R=%g, A=%d)", s, ds.radius_m, ds.sectors);
    d.label = label, d.group = "descriptor", d.setting = s;
    v.push_back(d);
  }
  const MethodSpec best = BestMethod();
  v.push_back(best);
  if (!ablations) return v;
  auto ablation = [&](const std::string& key, const std::string& note, auto change) {
    MethodSpec a = best;
    a.key = key, a.label = key, a.group = "ablation", a.note = note;
    change(a.localize);
    v.push_back(a);
  };
  ablation("abl_verify_10", "10 maps verified instead of 20", [](LocalizeOptions& o) { o.verify_maps = 10; });
  ablation("abl_verify_40", "40 maps verified (100 hypotheses) instead of 20", [](LocalizeOptions& o) {
    o.verify_maps = 40, o.search.max_hypotheses = 100;
  });
  ablation("abl_rank_by_share", "hits ranked by their score (share within 0.3 m), no closeness blended in",
           [](LocalizeOptions& o) { o.closeness_weight = 0; });
  ablation("abl_no_route_diversity", "route neighbours of chosen maps verified too",
           [](LocalizeOptions& o) { o.maps_per_route_window = 0; });
  ablation("abl_route_2", "two maps per route window verified",
           [](LocalizeOptions& o) { o.maps_per_route_window = 2; });
  ablation("abl_no_reverse_conflicts", "verification score without reverse conflicts",
           [](LocalizeOptions& o) { o.reverse_conflict_weight = 0; });
  ablation("abl_no_conflicts", "verification score without conflicts", [](LocalizeOptions& o) {
    o.conflict_weight = 0;
  });
  ablation("abl_no_refine", "best hit's pose not refined at full resolution",
           [](LocalizeOptions& o) { o.refine_best = false; });
  ablation("abl_no_self_rival", "no second pose of the best map looked for",
           [](LocalizeOptions& o) { o.self_rival_radius_m = 0; });
  ablation("abl_whole_map_5", "the first 5 maps searched over their whole extent",
           [](LocalizeOptions& o) { o.whole_map_maps = 5; });
  ablation("abl_neighbours_5", "5 nearest stored features per query feature instead of 10",
           [](LocalizeOptions& o) { o.search.neighbours = 5; });
  ablation("abl_neighbours_20", "20 nearest stored features per query feature instead of 10",
           [](LocalizeOptions& o) { o.search.neighbours = 20; });
  ablation("abl_radius_6", "place descriptor radius 6 m instead of 4 m", [](LocalizeOptions& o) {
    o.features.radius_m = 6.0;
  });
  ablation("abl_radius_3", "place descriptor radius 3 m instead of 4 m", [](LocalizeOptions& o) {
    o.features.radius_m = 3.0;
  });
  ablation("abl_min_evidence_0", "every change mask reported (no minimum evidence)",
           [](LocalizeOptions& o) { o.changes.min_evidence = 0; });
  return v;
}

// ---------------------------------------------------------------------------
// Descriptor cache: one Lmd per (configuration, map) and per (configuration,
// changed query).

struct DescKey {
  Planner planner;
  int setting;
  int word_bits;
  bool operator<(const DescKey& o) const {
    return std::tie(planner, setting, word_bits) < std::tie(o.planner, o.setting, o.word_bits);
  }
};

struct DescSet {
  std::vector<Lmd> db;                         // per map
  std::vector<std::vector<PoseFeature>> db_pf; // per map, sorted
  std::vector<double> db_ms;                   // describe time per map
  std::vector<Lmd> q;                          // per query (changed copy)
  std::vector<std::vector<PoseFeature>> q_pf;
  std::vector<double> q_ms;
};

struct Plans {
  std::vector<Frame> cog, cor;      // per map
  std::vector<double> ms;           // planning time per map
  std::vector<Frame> q_cog, q_cor;  // per query (changed copy)
  std::vector<double> q_ms;
  const Frame& Db(Planner p, size_t i) const { return p == Planner::kCoG ? cog[i] : cor[i]; }
  const Frame& Q(Planner p, size_t i) const { return p == Planner::kCoG ? q_cog[i] : q_cor[i]; }
};

const IndexOptions kIndexOptions{};

class Describers {
 public:
  Describers(const Dataset& d, const Plans& plans, int threads) : d_(d), plans_(plans), threads_(threads) {}

  const DescSet& Get(const DescKey& key) {
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    DescSet& s = cache_[key];
    DescriberOptions o;
    o.setting = PaperDescriptorSetting(key.setting);
    o.word_bits = key.word_bits;
    const size_t n = d_.maps.size(), nq = d_.queries.size();
    s.db.resize(n), s.db_pf.resize(n), s.db_ms.resize(n);
    s.q.resize(nq), s.q_pf.resize(nq), s.q_ms.resize(nq);
    char label[128];
    std::snprintf(label, sizeof label, "%s: describing (%s, #%d, %d bits)", d_.name.c_str(),
                  PlannerName(key.planner), key.setting, key.word_bits);
    ProgressBar bar(label, n + nq);
    std::mutex mu;
    size_t done = 0;
    ParallelFor(n + nq, threads_, [&](size_t k) {
      const auto t0 = Clock::now();
      const bool is_q = k >= n;
      const size_t i = is_q ? k - n : k;
      const LocalMap& map = is_q ? d_.queries[i].changed : d_.maps[i];
      const Frame& frame = is_q ? plans_.Q(key.planner, i) : plans_.Db(key.planner, i);
      Lmd lmd = Describe(map, frame, o);
      Result<std::vector<PoseFeature>> pf = ToPoseFeatures(lmd, kIndexOptions);
      std::vector<PoseFeature> f = pf.ok() ? std::move(pf).value() : std::vector<PoseFeature>{};
      const double ms = MsSince(t0);
      if (is_q) {
        s.q[i] = std::move(lmd), s.q_pf[i] = std::move(f), s.q_ms[i] = ms;
      } else {
        s.db[i] = std::move(lmd), s.db_pf[i] = std::move(f), s.db_ms[i] = ms;
      }
      std::lock_guard<std::mutex> lock(mu);
      bar.Update(++done);
    });
    bar.Done();
    return s;
  }

 private:
  const Dataset& d_;
  const Plans& plans_;
  int threads_;
  std::map<DescKey, DescSet> cache_;
};

Plans PlanAll(const Dataset& d, int threads) {
  Plans p;
  const size_t n = d.maps.size(), nq = d.queries.size();
  p.cog.resize(n), p.cor.resize(n), p.ms.resize(n);
  p.q_cog.resize(nq), p.q_cor.resize(nq), p.q_ms.resize(nq);
  ProgressBar bar(d.name + ": planning viewpoints", n + nq);
  std::mutex mu;
  size_t done = 0;
  ParallelFor(n + nq, threads, [&](size_t k) {
    const auto t0 = Clock::now();
    const bool is_q = k >= n;
    const size_t i = is_q ? k - n : k;
    const ViewpointPlan plan = PlanViewpointDetailed(is_q ? d.queries[i].changed : d.maps[i]);
    const double ms = MsSince(t0);
    if (is_q) {
      p.q_cog[i] = plan.cog, p.q_cor[i] = plan.cor, p.q_ms[i] = ms;
    } else {
      p.cog[i] = plan.cog, p.cor[i] = plan.cor, p.ms[i] = ms;
    }
    std::lock_guard<std::mutex> lock(mu);
    bar.Update(++done);
  });
  bar.Done();
  return p;
}

// ---------------------------------------------------------------------------
// Paper methods: one query scored against all its candidates.

struct Scored {
  size_t db = 0;       // map index
  double score = 0.0;  // first stage
  int orientation = 0;
  Point2 offset;       // planned frames
};

struct QueryRun {
  QueryOutcome outcome;
  std::vector<Scored> top;  // final order, at most kKeep
};

constexpr size_t kKeep = 10;

QueryRun RunPaperQuery(const Dataset& d, size_t qi, const MethodSpec& m, const Plans& plans, const DescSet& s) {
  const EvalQuery& q = d.queries[qi];
  QueryRun run;
  const auto t0 = Clock::now();
  RetrieveOptions ro;
  ro.method = m.method;
  ro.max_offset_m = m.max_offset_m;
  const std::vector<PoseFeature>& query_pf = m.stationary ? s.db_pf[q.map] : s.q_pf[qi];
  const Frame& query_frame = m.stationary ? plans.Db(m.planner, q.map) : plans.Q(m.planner, qi);
  const double prep_ms = m.stationary ? plans.ms[q.map] + s.db_ms[q.map] : plans.q_ms[qi] + s.q_ms[qi];
  const PreparedLmdQuery pq = PrepareLmdQuery(query_pf, kIndexOptions, ro);
  KernelScratch scratch;
  std::vector<Scored> all(q.candidates.size());
  for (size_t c = 0; c < q.candidates.size(); ++c) {
    const size_t j = q.candidates[c];
    const std::vector<PoseFeature>& db = s.db_pf[j];
    all[c].db = j;
    if (m.method == Method::kBow) {
      all[c].score = ScoreBowMap(pq, db.data(), db.size());
      continue;
    }
    const KernelScore k = ScoreLmdMap(pq, db.data(), db.size(), &scratch);
    all[c].score = k.score, all[c].orientation = k.orientation;
    all[c].offset = {k.offset_x * kIndexOptions.pose_quantum_m, k.offset_y * kIndexOptions.pose_quantum_m};
  }
  std::vector<size_t> order(all.size());
  std::iota(order.begin(), order.end(), 0);
  const size_t keep = std::min(kKeep, all.size());
  std::partial_sort(order.begin(), order.begin() + keep, order.end(), [&](size_t a, size_t b) {
    return all[a].score != all[b].score ? all[a].score > all[b].score : all[a].db < all[b].db;
  });
  run.outcome.ms = prep_ms + MsSince(t0);
  std::vector<double> scores(all.size());
  size_t target = 0;
  for (size_t c = 0; c < all.size(); ++c) {
    scores[c] = all[c].score;
    if (all[c].db == q.relevant) target = c;
  }
  run.outcome.rank = RankOfTarget(scores, target);
  run.outcome.candidates = all.size();
  run.outcome.place_counted = !q.places.empty();
  for (size_t r = 0; r < keep; ++r) {
    const Scored& h = all[order[r]];
    if (h.score <= 0) break;  // unscored maps are not hits
    run.top.push_back(h);
    if (run.outcome.first_place_hit < 0 && d.ShowsPlace(q, h.db)) run.outcome.first_place_hit = static_cast<int>(r);
  }
  if (!run.top.empty() && run.outcome.first_place_hit == 0 && m.method == Method::kLmd) {
    const Scored& h = run.top[0];
    run.outcome.has_pose = true;
    PoseError(RelativePose(query_frame, plans.Db(m.planner, h.db), h.orientation, h.offset),
              d.TruePose(q.map, h.db), &run.outcome.pose_err_m, &run.outcome.pose_err_deg);
  }
  return run;
}

// The paper's change detector over a paper method's hits: the first
// 1-based mask rank at which the task succeeds (0 = never), per threshold;
// masks and false ones among the top 10 at the default threshold.
void EvalPaperChangeTask(const Dataset& d, size_t qi, const QueryRun& run, const DescSet& s,
                         std::vector<size_t>* first, size_t* masks_default, size_t* false_default) {
  const EvalQuery& q = d.queries[qi];
  std::vector<ChangeCandidate> cands;
  for (size_t r = 0; r < run.top.size(); ++r) {
    ChangeCandidate c;
    c.hit.map_id = run.top[r].db, c.hit.score = run.top[r].score, c.hit.rank = r;
    c.hit.orientation = run.top[r].orientation, c.hit.offset = run.top[r].offset;
    c.db = &s.db[run.top[r].db];
    cands.push_back(c);
  }
  const std::vector<double>& ts = ChangeThresholds();
  first->assign(ts.size(), 0);
  for (size_t t = 0; t < ts.size(); ++t) {
    ChangeDetectorOptions o;
    o.threshold = std::max(ts[t], 1e-9);  // T = 0: every feature with r > 0 (the detector needs T > 0)
    Result<std::vector<ChangeMask>> masks = DetectChanges(s.q[qi], cands, o);
    if (!masks.ok()) continue;
    size_t wrong_top10 = 0;
    for (size_t r = 0; r < masks->size(); ++r) {
      const ChangeMask& mk = (*masks)[r];
      const bool ok = d.ShowsPlace(q, mk.db_map_id) && MaskHitsChange(mk.points, q.changed_points, kMaskHitM);
      if (ok && (*first)[t] == 0) (*first)[t] = r + 1;
      if (!ok && r < 10) ++wrong_top10;
    }
    if (ts[t] == kDefaultChangeThreshold) {
      *masks_default = std::min<size_t>(masks->size(), 10);
      *false_default = wrong_top10;
    }
  }
}

// ---------------------------------------------------------------------------
// The pipeline: every map of the dataset stored in a MemoryCollection, each
// query (its changed copy, or the map itself when stationary) localised with
// its candidates only, as lmdd would with the others excluded.

// What a collection's preparation depends on (the rest of LocalizeOptions
// applies per query).
std::string PreparationKey(const LocalizeOptions& o) {
  char key[160];
  std::snprintf(key, sizeof key, "%g/%d/%g/%zu/%g/%g", o.features.radius_m, o.features.shells,
                o.features.interest_cell_m, o.features.max_features, o.match.map.cell_m, o.match.map.sparse_cell_m);
  return key;
}

struct Collection {
  std::vector<PreparedPlace> places;  // per map
  MemoryCollection maps;
};

std::unique_ptr<Collection> BuildCollection(const Dataset& d, const LocalizeOptions& options, int threads) {
  auto c = std::make_unique<Collection>();
  c->places.resize(d.maps.size());
  ProgressBar bar(d.name + ": preparing the collection", d.maps.size());
  std::mutex mu;
  size_t done = 0;
  ParallelFor(d.maps.size(), threads, [&](size_t i) {
    c->places[i] = PreparePlace(d.maps[i], options);
    std::lock_guard<std::mutex> lock(mu);
    bar.Update(++done);
  });
  bar.Done();
  for (size_t i = 0; i < d.maps.size(); ++i) {
    if (!d.maps[i].points.empty()) c->maps.Add(i, c->places[i], MapSource::Route{0, i + 1});  // one robot: the log
  }
  return c;
}

Answer ToAnswer(const Localization& l, double cpu_ms) {
  Answer a;
  for (const LocalizedHit& h : l.hits) {
    a.hits.push_back({static_cast<size_t>(h.map_id), h.pose, h.score, h.agrees_with_best});
  }
  a.localized = l.verdict.sure;
  a.confidence = l.verdict.confidence;
  a.rival_score = l.verdict.rival_score;
  for (const ChangeMask& m : l.changes) {
    const auto hit = std::find_if(l.hits.begin(), l.hits.end(),
                                  [&](const LocalizedHit& h) { return h.map_id == m.db_map_id; });
    if (hit == l.hits.end()) continue;  // its map is past top_k: lmdd could not send it either
    a.masks.push_back({static_cast<size_t>(m.db_map_id), hit->pose, m.points});
  }
  a.cpu_ms = cpu_ms;
  return a;
}

struct PipelineRun {
  QueryOutcome outcome;    // the paper's scoring
  AnswerOutcome answer;    // verdict, masks, cost
};

PipelineRun RunPipelineQuery(const Dataset& d, size_t qi, const MethodSpec& m, const Collection& c) {
  const EvalQuery& q = d.queries[qi];
  const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
  const double cpu0 = ThreadCpuMs();
  const auto t0 = Clock::now();
  const LocalQuery query = m.stationary ? PrepareLocalQuery(d.maps[q.map], m.localize, &c.places[q.map])
                                        : PrepareLocalQuery(q.changed, m.localize);
  const Localization l = Localize(query, c.maps, m.localize,
                                  [&](uint64_t id) { return candidates.count(static_cast<size_t>(id)) == 0; }, {},
                                  !m.stationary);
  PipelineRun run;
  run.answer = ScoreAnswer(d, q, ToAnswer(l, ThreadCpuMs() - cpu0), !m.stationary);
  run.outcome.ms = MsSince(t0);
  // The paper's rank: the pipeline ranks the maps it verified; the others
  // tie behind them (RankOfTarget counts ties half).
  std::vector<double> scores(q.candidates.size(), 0.0);
  size_t target = 0;
  std::unordered_map<size_t, size_t> at;
  for (size_t k = 0; k < q.candidates.size(); ++k) {
    at[q.candidates[k]] = k;
    if (q.candidates[k] == q.relevant) target = k;
  }
  for (size_t r = 0; r < l.hits.size(); ++r) {
    const auto it = at.find(static_cast<size_t>(l.hits[r].map_id));
    if (it != at.end()) scores[it->second] = static_cast<double>(l.hits.size() - r);
  }
  run.outcome.rank = RankOfTarget(scores, target);
  run.outcome.candidates = q.candidates.size();
  run.outcome.place_counted = run.answer.place_counted;
  run.outcome.first_place_hit = run.answer.first_place_hit;
  run.outcome.has_pose = run.answer.pose_known;
  run.outcome.pose_err_m = run.answer.pose_err_m, run.outcome.pose_err_deg = run.answer.pose_err_deg;
  return run;
}

// ---------------------------------------------------------------------------
// One dataset, every method.

struct RunOptions {
  int threads = 2;
  size_t max_queries = 0;  // 0 = all (debug: every n-th query to keep this many)
};

ChangeResult SummarizeChange(const std::vector<std::vector<size_t>>& first, const std::vector<size_t>& masks,
                             const std::vector<size_t>& false_alarms) {
  ChangeResult c;
  c.ks = LogSteps(1000);
  const std::vector<double>& ts = ChangeThresholds();
  std::vector<std::vector<size_t>> per_t(ts.size());
  size_t total_masks = 0, total_false = 0;
  for (size_t k = 0; k < first.size(); ++k) {
    if (first[k].empty()) continue;
    ++c.tasks;
    for (size_t t = 0; t < ts.size(); ++t) per_t[t].push_back(first[k][t]);
    total_masks += masks[k], total_false += false_alarms[k];
  }
  for (size_t t = 0; t < ts.size(); ++t) {
    c.curves[ts[t]] = SuccessCurve(per_t[t], c.ks);
    if (ts[t] == kDefaultChangeThreshold) {
      const std::vector<double> at = SuccessCurve(per_t[t], {1, 10});
      c.success_at_1 = at[0], c.success_at_10 = at[1];
    }
  }
  c.false_alarm_rate = total_masks ? static_cast<double>(total_false) / total_masks : 0.0;
  c.masks_mean = c.tasks ? static_cast<double>(total_masks) / c.tasks : 0.0;
  return c;
}

DatasetResults EvaluateDataset(const Dataset& d, const std::vector<MethodSpec>& specs, const RunOptions& ro) {
  DatasetResults res;
  res.name = d.name;
  res.maps = d.maps.size();
  std::vector<size_t> qs;
  const size_t stride = ro.max_queries && d.queries.size() > ro.max_queries
                            ? (d.queries.size() + ro.max_queries - 1) / ro.max_queries : 1;
  for (size_t i = 0; i < d.queries.size(); i += stride) qs.push_back(i);
  res.queries = qs.size();

  const bool paper = std::any_of(specs.begin(), specs.end(), [](const MethodSpec& m) { return !m.pipeline; });
  Plans plans;
  if (paper) plans = PlanAll(d, ro.threads);
  Describers describers(d, plans, ro.threads);
  std::map<std::string, std::unique_ptr<Collection>> collections;  // by PreparationKey
  for (const MethodSpec& m : specs) {
    std::vector<QueryOutcome> outcomes(qs.size());
    ProgressBar bar(d.name + ": " + m.key, qs.size());
    std::mutex mu;
    size_t done = 0;
    if (m.pipeline) {
      std::unique_ptr<Collection>& c = collections[PreparationKey(m.localize)];
      if (!c) c = BuildCollection(d, m.localize, ro.threads);
      std::vector<AnswerOutcome> answers(qs.size());
      ParallelFor(qs.size(), ro.threads, [&](size_t k) {
        const PipelineRun run = RunPipelineQuery(d, qs[k], m, *c);
        outcomes[k] = run.outcome, answers[k] = run.answer;
        std::lock_guard<std::mutex> lock(mu);
        bar.Update(++done);
      });
      bar.Done();
      res.methods[m.key] = Summarize(outcomes);
      res.pipeline[m.key] = SummarizeAnswers(answers);
      continue;
    }
    const DescSet& s = describers.Get({m.planner, m.setting, m.word_bits});
    std::vector<std::vector<size_t>> first(qs.size());
    std::vector<size_t> masks(qs.size(), 0), false_alarms(qs.size(), 0);
    ParallelFor(qs.size(), ro.threads, [&](size_t k) {
      const size_t qi = qs[k];
      const QueryRun run = RunPaperQuery(d, qi, m, plans, s);
      outcomes[k] = run.outcome;
      if (m.change_eval && d.queries[qi].change_ok && !m.stationary) {
        EvalPaperChangeTask(d, qi, run, s, &first[k], &masks[k], &false_alarms[k]);
      }
      std::lock_guard<std::mutex> lock(mu);
      bar.Update(++done);
    });
    bar.Done();
    res.methods[m.key] = Summarize(outcomes);
    if (m.change_eval) {
      const ChangeResult c = SummarizeChange(first, masks, false_alarms);
      res.method_change[m.key] = c;
      if (res.change_method.empty()) res.change_method = m.key, res.change = c;
    }
  }
  return res;
}

std::string Now() {
  char buf[64];
  const std::time_t t = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
  return buf;
}

std::string Machine() {
  std::string cpu = "unknown CPU";
  if (std::FILE* f = std::fopen("/proc/cpuinfo", "r")) {
    char line[512];
    while (std::fgets(line, sizeof line, f)) {
      std::string s = line;
      if (s.rfind("model name", 0) == 0) {
        cpu = s.substr(s.find(':') + 2);
        if (!cpu.empty() && cpu.back() == '\n') cpu.pop_back();
        break;
      }
    }
    std::fclose(f);
  }
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return cpu + ", " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " cores online";
}

}  // namespace

int RunRetrieval(int argc, char** argv) {
  Flags args({"log", "out", "methods", "threads", "max-queries", "seed", "truth-frame", "truth-odom"}, {"ablations"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval retrieval: %s\n", args.error().c_str());
    return 2;
  }
  const std::string out_dir = args.Get("out", "out/retrieval");
  RunOptions ro;
  DatasetOptions dopt;
  dopt.truth_frame = args.Get("truth-frame");
  dopt.truth_odom = args.Get("truth-odom");
  uint64_t threads = 2, max_queries = 0;
  if (!args.Count("threads", 1, 256, 2, &threads) || !args.Count("max-queries", 0, 1000000000, 0, &max_queries) ||
      !args.Count("seed", 0, UINT64_MAX, 1, &dopt.seed)) {
    std::fprintf(stderr, "lmd-eval retrieval: %s\n", args.error().c_str());
    return 2;
  }
  ro.threads = static_cast<int>(threads);
  ro.max_queries = static_cast<size_t>(max_queries);
  // The logs are looked for once the options are checked: a mistyped option is refused first.
  std::string no_logs;
  const std::vector<std::string> logs = LogsToMeasure(args.GetAll("log"), &no_logs);
  if (logs.empty()) {
    std::fprintf(stderr, "lmd-eval retrieval: %s\n", no_logs.c_str());
    return 2;
  }
  dopt.threads = ro.threads;
  // --methods picks by key among all methods, ablation rows included.
  std::vector<MethodSpec> specs = DefaultMethods(args.Has("ablations") || args.Has("methods"));
  if (args.Has("methods")) {  // comma-separated keys to keep
    std::vector<MethodSpec> kept;
    std::string key;
    std::istringstream keys(args.Get("methods"));
    while (std::getline(keys, key, ',')) {
      auto it = std::find_if(specs.begin(), specs.end(), [&](const MethodSpec& m) { return m.key == key; });
      if (it == specs.end()) {
        std::fprintf(stderr, "lmd-eval retrieval: unknown method '%s' in --methods\n", key.c_str());
        return 2;
      }
      kept.push_back(*it);
    }
    specs = kept;
  }
  RunInfo info;
  info.command = "lmd-eval retrieval";
  for (int i = 0; i < argc; ++i) info.command += std::string(" ") + argv[i];
  info.date = Now();
  info.machine = Machine();
  info.seed = dopt.seed;
  info.threads = ro.threads;
  const auto start = Clock::now();
  std::vector<DatasetResults> results;
  for (const std::string& log : logs) {
    Result<Dataset> d = LoadDataset(log, dopt);
    if (!d.ok()) {
      std::fprintf(stderr, "lmd-eval retrieval: %s\n", d.status().ToString().c_str());
      return 1;
    }
    results.push_back(EvaluateDataset(*d, specs, ro));
    const DatasetResults& r = results.back();
    std::fprintf(stderr, "%s: %zu maps, %zu queries\n", r.name.c_str(), r.maps, r.queries);
    for (const MethodSpec& m : specs) {
      const RetrievalSummary& s = r.methods.at(m.key);
      std::fprintf(stderr, "  %-20s ANR %5.1f%%  R@1 %.2f  top1%% %.2f  top10%% %.2f  place@1 %.2f  @5 %.2f  pose %.3f m %.2f deg  %.1f ms\n",
                   m.key.c_str(), s.anr, s.recall_at_1, s.top1, s.top10, s.place_at_1, s.place_at_5,
                   s.pose_err_m_median, s.pose_err_deg_median, s.ms_per_query);
      const auto p = r.pipeline.find(m.key);
      if (p != r.pipeline.end()) {
        std::fprintf(stderr, "  %-20s sure %.2f right %.4f, change top mask %.2f false %.2f, cpu p50 %.1f ms\n", "",
                     p->second.localized_share, p->second.localized_precision, p->second.change_success_at_1,
                     p->second.false_mask_share, p->second.cpu_ms_p50);
      }
    }
    if (!r.change_method.empty()) {
      std::fprintf(stderr, "  change (%s): %zu tasks, success@1 %.2f @10 %.2f, false alarms %.2f\n",
                   r.change_method.c_str(), r.change.tasks, r.change.success_at_1, r.change.success_at_10,
                   r.change.false_alarm_rate);
    }
  }
  info.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (!WriteResults(out_dir, specs, results, info)) {
    std::fprintf(stderr, "lmd-eval retrieval: cannot write into %s\n", out_dir.c_str());
    return 1;
  }
  std::printf("wrote %s/results.json, report.md and plots (%.0f s)\n", out_dir.c_str(), info.seconds);
  return 0;
}

}  // namespace lmd::eval
