// lmd-eval served: the evaluation protocol run through a live lmdd, as a
// fleet's robots see it. Per log: every local map is inserted in its own
// frame with its trajectory and scans (robot = the log, sequence = its
// number), then each map is sent back as a Retrieve query with the maps
// within 10 m of travel excluded, and its copy with a simulated change as a
// DetectChanges query. lmdd's answers (hits, poses, verdict, masks, its CPU
// per call) are scored against the logs' ground truth (answer_scoring.h).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "bench/eval/answer_scoring.h"
#include "bench/common/flags.h"
#include "core/util/split.h"
#include "bench/eval/commands.h"
#include "bench/eval/data_paths.h"
#include "bench/eval/eval_dataset.h"
#include "bench/eval/lmdd_process.h"
#include "bench/eval/sequence_context.h"
#include "bench/eval/served_report.h"
#include "client/lmd_client.h"
#include "core/util/progress_bar.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/pose_noise.h"
#include "proto/convert.h"

namespace lmd::eval {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kInsertBatch = 25;

// How each query is asked (DESIGN.md §6).
enum class QueryMode {
  kGlobal,    // the map alone
  kPrior,     // with a prior: the map's true pose in the log's frame, perturbed
  kSequence,  // with the robot's earlier maps and perturbed odometry to them
};

struct ServedOptions {
  std::string collection_prefix = "served-";
  QueryMode mode = QueryMode::kGlobal;
  // Maps inserted with their pose in the log's frame as pose_hint (a site
  // map built by the robots' own SLAM): prior and sequence queries need it.
  bool anchored = false;
  // Priors: the true pose with this noise (--mode tracking: kTrackingPrior).
  PoseNoise prior_noise = kRoughPrior;
  SequenceShape sequence;  // sequences: how many maps, how far apart
  size_t max_queries = 0;  // per log, 0 = every map
  int threads = 1;         // concurrent queries
  bool changes = true;
  uint32_t verify = 0;     // verify_candidates of each request (0: lmdd's)
};

Status Insert(const client::LmdClient& client, const Dataset& d, const std::string& collection, bool anchored) {
  ProgressBar bar(d.name + ": inserting", d.maps.size());
  for (size_t first = 0; first < d.maps.size(); first += kInsertBatch) {
    v1::InsertMapsRequest request;
    for (size_t i = first; i < std::min(d.maps.size(), first + kInsertBatch); ++i) {
      if (d.maps[i].points.empty()) continue;
      v1::InsertMapRequest* insert = request.add_maps();
      insert->mutable_metadata()->set_collection(collection);
      insert->mutable_metadata()->set_map_id(d.maps[i].id);
      insert->mutable_metadata()->set_robot_id(d.name);
      insert->mutable_metadata()->set_sequence(i + 1);
      if (anchored) *insert->mutable_metadata()->mutable_pose_hint() = ToProto(d.maps[i].truth.global_frame);
      *insert->mutable_map() = ToProto(d.maps[i]);
    }
    if (request.maps_size() == 0) continue;
    v1::InsertMapsResponse response;
    const grpc::Status status = client.InsertMaps(request, &response);
    if (!status.ok()) {
      bar.Abandon();
      return Status::IoError("inserting " + d.name + " maps: " + status.error_message());
    }
    bar.Update(std::min(d.maps.size(), first + kInsertBatch));
  }
  bar.Done();
  return Status::Ok();
}

template <typename Hit>
Answer::Hit ToAnswerHit(const Hit& hit, const std::unordered_map<std::string, size_t>& index_of, bool* known) {
  const auto it = index_of.find(hit.map_id());
  *known = it != index_of.end();
  return {*known ? it->second : 0, FromProto(hit.pose()), hit.score(), hit.agrees_with_best()};
}

Answer FromResponse(const v1::RetrieveResponse& r, const std::unordered_map<std::string, size_t>& index_of) {
  Answer a;
  for (const v1::MapHit& hit : r.hits()) {
    bool known = false;
    const Answer::Hit h = ToAnswerHit(hit, index_of, &known);
    if (known) a.hits.push_back(h);
  }
  a.localized = r.localization().localized();
  a.confidence = r.localization().confidence();
  a.rival_score = r.localization().rival_score();
  if (r.localization().has_collection_pose()) a.site_pose = FromProto(r.localization().collection_pose());
  // The covariance is of the response's first hit: a.hits[0] only if it was known.
  if (r.hits_size() > 0 && index_of.count(r.hits(0).map_id()) && r.localization().has_pose_covariance()) {
    a.pose_covariance = FromProto(r.localization().pose_covariance());
  }
  a.cpu_ms = r.server_cpu_ms();
  return a;
}

Answer FromResponse(const v1::DetectChangesResponse& r, const std::unordered_map<std::string, size_t>& index_of) {
  Answer a;
  std::vector<std::pair<uint32_t, Answer::Mask>> masks;  // (rank, mask)
  for (const v1::ChangeHit& change_hit : r.hits()) {
    bool known = false;
    const Answer::Hit h = ToAnswerHit(change_hit.hit(), index_of, &known);
    if (!known) continue;
    a.hits.push_back(h);
    for (const v1::ChangeMask& m : change_hit.masks()) {
      Answer::Mask mask;
      mask.db = h.db;
      mask.pose = h.pose;
      for (int i = 0; i < m.x_size(); ++i) mask.points.push_back({m.x(i), m.y(i)});
      masks.push_back({m.rank(), std::move(mask)});
    }
  }
  std::sort(masks.begin(), masks.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  for (auto& [rank, mask] : masks) a.masks.push_back(std::move(mask));
  a.localized = r.localization().localized();
  a.confidence = r.localization().confidence();
  a.rival_score = r.localization().rival_score();
  if (r.localization().has_collection_pose()) a.site_pose = FromProto(r.localization().collection_pose());
  if (r.hits_size() > 0 && index_of.count(r.hits(0).hit().map_id()) && r.localization().has_pose_covariance()) {
    a.pose_covariance = FromProto(r.localization().pose_covariance());
  }
  a.cpu_ms = r.server_cpu_ms();
  return a;
}

// The prior or the sequence of query `q` (seeded by the query map's index).
template <typename Request>
void AddContext(const Dataset& d, const EvalQuery& q, const ServedOptions& options, uint64_t seed, Request* request) {
  std::mt19937_64 rng(seed ^ (0x9E3779B97F4A7C15ULL * (q.map + 1)));
  const Pose2 truth = d.maps[q.map].truth.global_frame;
  if (options.mode == QueryMode::kPrior) {
    v1::Prior* prior = request->mutable_prior();
    *prior->mutable_pose() = ToProto(PerturbedPose(truth, options.prior_noise, rng));
    prior->set_radius_m(options.prior_noise.radius_m);
    prior->set_heading_sigma_rad(options.prior_noise.sigma_deg * M_PI / 180.0);
  }
  if (options.mode == QueryMode::kSequence) {
    for (const EarlierMap& e : EarlierMaps(d, q, options.sequence, &rng)) {
      v1::SequenceMap* step = request->add_sequence();
      *step->mutable_map() = ToProto(d.maps[e.map]);
      *step->mutable_in_query() = ToProto(e.in_newest);
      step->set_travel_m(e.travel_m);
    }
  }
}

// The query as the protocol asks it (a sequence query: without the stored
// maps around its earlier maps, WithoutSequenceNeighbours).
EvalQuery FairQuery(const Dataset& d, EvalQuery q, const ServedOptions& options) {
  if (options.mode != QueryMode::kSequence) return q;
  return WithoutSequenceNeighbours(d, std::move(q), options.sequence);
}

struct QueryRecord {
  AnswerOutcome still, changed;
  double best_score = 0, rival_score = 0, changed_best = 0, changed_rival = 0;
  uint32_t agreeing = 0;
  std::string top_hit;  // the top hit's map id ("" without a hit)
  std::string vote_lead;  // Localization.vote_lead ("" where absent)
};

Result<ServedLog> RunLog(const client::LmdClient& client, const Dataset& d, const ServedOptions& options,
                         uint64_t seed) {
  const std::string collection = options.collection_prefix + d.name;
  v1::ListCollectionsResponse listed;
  grpc::Status status = client.ListCollections(&listed);
  if (!status.ok()) return Status::IoError("listing collections: " + status.error_message());
  for (const v1::CollectionInfo& c : listed.collections()) {
    if (c.name() == collection && c.maps() > 0) {
      return Status::InvalidArgument("collection '" + collection + "' already holds maps: use a fresh lmdd");
    }
  }
  Status inserted = Insert(client, d, collection, options.anchored);
  if (!inserted.ok()) return inserted;

  std::unordered_map<std::string, size_t> index_of;
  for (size_t i = 0; i < d.maps.size(); ++i) index_of[d.maps[i].id] = i;
  std::vector<size_t> qs;
  const size_t stride = options.max_queries && d.queries.size() > options.max_queries
                            ? (d.queries.size() + options.max_queries - 1) / options.max_queries : 1;
  for (size_t i = 0; i < d.queries.size(); i += stride) qs.push_back(i);

  std::vector<QueryRecord> records(qs.size());
  std::atomic<size_t> next{0}, done{0};
  std::mutex mu;
  std::string error;
  ProgressBar bar(d.name + ": querying", qs.size());
  auto worker = [&] {
    for (size_t k = next++; k < qs.size(); k = next++) {
      const EvalQuery q = FairQuery(d, d.queries[qs[k]], options);
      const std::unordered_set<size_t> candidates(q.candidates.begin(), q.candidates.end());
      v1::RetrieveRequest retrieve;
      retrieve.set_collection(collection);
      *retrieve.mutable_map() = ToProto(d.maps[q.map]);
      retrieve.set_verify_candidates(options.verify);
      for (size_t j = 0; j < d.maps.size(); ++j) {
        if (candidates.count(j) == 0 && !d.maps[j].points.empty()) retrieve.add_exclude_map_ids(d.maps[j].id);
      }
      AddContext(d, q, options, seed, &retrieve);
      v1::RetrieveResponse answer;
      auto t0 = Clock::now();
      grpc::Status s = client.Retrieve(retrieve, &answer);
      const double wall = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (!s.ok()) {
        std::lock_guard<std::mutex> lock(mu);
        error = "Retrieve of " + d.maps[q.map].id + ": " + s.error_message();
        return;
      }
      QueryRecord& rec = records[k];
      Answer a = FromResponse(answer, index_of);
      a.wall_ms = wall;
      rec.still = ScoreAnswer(d, q, a, false);
      if (!a.hits.empty()) rec.top_hit = d.maps[a.hits[0].db].id;
      rec.best_score = answer.localization().best_score();
      rec.rival_score = answer.localization().rival_score();
      rec.agreeing = answer.localization().agreeing();
      if (answer.localization().has_vote_lead()) {
        char lead[32];
        std::snprintf(lead, sizeof lead, "%g", answer.localization().vote_lead());
        rec.vote_lead = lead;
      }
      if (options.changes) {
        v1::DetectChangesRequest detect;
        detect.set_collection(collection);
        *detect.mutable_map() = ToProto(q.changed);
        detect.set_verify_candidates(options.verify);
        *detect.mutable_exclude_map_ids() = retrieve.exclude_map_ids();
        if (retrieve.has_prior()) *detect.mutable_prior() = retrieve.prior();
        *detect.mutable_sequence() = retrieve.sequence();
        v1::DetectChangesResponse changes;
        t0 = Clock::now();
        s = client.DetectChanges(detect, &changes);
        const double changed_wall = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!s.ok()) {
          std::lock_guard<std::mutex> lock(mu);
          error = "DetectChanges of " + d.maps[q.map].id + ": " + s.error_message();
          return;
        }
        Answer c = FromResponse(changes, index_of);
        c.wall_ms = changed_wall;
        rec.changed = ScoreAnswer(d, q, c, true);
        rec.changed_best = changes.localization().best_score();
        rec.changed_rival = changes.localization().rival_score();
      }
      std::lock_guard<std::mutex> lock(mu);
      bar.Update(++done);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::max(1, options.threads); ++t) threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();
  if (!error.empty()) {
    bar.Abandon();
    return Status::IoError(error);
  }
  bar.Done();

  ServedLog log;
  log.name = d.name;
  log.maps = d.maps.size();
  std::vector<AnswerOutcome> still, changed;
  for (size_t k = 0; k < qs.size(); ++k) {
    const QueryRecord& r = records[k];
    still.push_back(r.still);
    if (options.changes) changed.push_back(r.changed);
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s,%s,%d,%d,%.4f,%.4f,%d,%d,%d,%.4f,%.4f,%.4f,%s,%u,%.3f,%.3f,%d,%zu,%zu,%zu,%.4f,%.4f,%.3f,%s,"
                  "%.4f,%.4f,%.3f,%.4f,%.3f,%s\n",
                  d.name.c_str(), d.maps[d.queries[qs[k]].map].id.c_str(), r.still.place_counted,
                  r.still.first_place_hit, r.still.pose_err_m, r.still.pose_err_deg, r.still.localized,
                  r.still.localized_right, r.still.wrong_pose_fits_better, r.still.confidence, r.best_score,
                  r.rival_score, RivalName(r.still.rival), r.agreeing, r.still.cpu_ms, r.still.wall_ms,
                  r.changed.localized, r.changed.first_change_mask, r.changed.masks, r.changed.false_masks,
                  r.changed_best, r.changed_rival, r.changed.cpu_ms, r.top_hit.c_str(),
                  r.still.site_known ? r.still.site_err_m : -1.0, r.still.site_known ? r.still.site_err_deg : -1.0,
                  r.still.pose_d2, r.still.position_sd_m, r.still.heading_sd_deg, r.vote_lead.c_str());
    log.query_lines += line;
  }
  log.still = SummarizeAnswers(still);
  if (options.changes) log.changed = SummarizeAnswers(changed);
  return log;
}

std::string Now() {
  char buf[64];
  const std::time_t t = std::time(nullptr);
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&t));
  return buf;
}

}  // namespace

int RunServed(int argc, char** argv) {
  Flags args(WithSensorFlags({"log", "out", "mode", "lmdd", "server", "threads", "max-queries", "verify", "seed",
                              "truth-frame", "truth-odom", "tuned-on"}),
             {"no-changes", "anchor"});
  if (!args.Parse(argc, argv)) {
    std::fprintf(stderr, "lmd-eval served: %s\n", args.error().c_str());
    return 2;
  }
  ServedOptions options;
  DatasetOptions dataset;
  dataset.every_map = true;
  dataset.truth_frame = args.Get("truth-frame");
  dataset.truth_odom = args.Get("truth-odom");
  uint64_t max_queries = 0, threads = 1, verify = 0;
  if (!SensorFromFlags(args, &dataset) || !args.Count("max-queries", 0, 1000000000, 0, &max_queries) ||
      !args.Count("threads", 1, 256, 1, &threads) || !args.Count("verify", 0, 1000000, 0, &verify) ||
      !args.Count("seed", 0, UINT64_MAX, 1, &dataset.seed)) {
    std::fprintf(stderr, "lmd-eval served: %s\n", args.error().c_str());
    return 2;
  }
  options.max_queries = static_cast<size_t>(max_queries);
  options.threads = static_cast<int>(threads);
  options.verify = static_cast<uint32_t>(verify);
  options.changes = !args.Has("no-changes");
  const std::string mode = args.Get("mode", "global");
  if (mode == "prior") {
    options.mode = QueryMode::kPrior;
  } else if (mode == "tracking") {
    options.mode = QueryMode::kPrior;
    options.prior_noise = kTrackingPrior;
  } else if (mode == "sequence") {
    options.mode = QueryMode::kSequence;
  } else if (mode != "global") {
    std::fprintf(stderr, "lmd-eval served: --mode is global, prior, tracking or sequence, not '%s'\n", mode.c_str());
    return 2;
  }
  // The options are checked first: a mistyped one is refused before any log is looked for.
  std::string no_logs;
  const std::vector<std::string> logs = LogsToMeasure(args.GetAll("log"), &no_logs);
  if (logs.empty()) {
    std::fprintf(stderr, "lmd-eval served: %s\n", no_logs.c_str());
    return 2;
  }
  options.anchored = args.Has("anchor") || options.mode != QueryMode::kGlobal;
  options.collection_prefix = "served-" + mode + "-";
  const std::vector<std::string> tuned_on =
      args.Has("tuned-on") ? SplitCommas(args.Get("tuned-on")) : DefaultTunedOn();
  const std::string out_dir = args.Get("out", "out/served");

  std::string target = args.Get("server");
  std::optional<LmddProcess> lmdd;
  const std::string work = (std::filesystem::temp_directory_path() / ("lmd-eval-served-" + std::to_string(getpid()))).string();
  if (target.empty()) {
    const std::string binary = args.Get("lmdd", LmddBesideThisBinary());
    if (binary.empty()) {
      std::fprintf(stderr, "lmd-eval served: no lmdd found next to lmd-eval: give --lmdd PATH or --server HOST:PORT\n");
      return 2;
    }
    Result<LmddProcess> started = LmddProcess::Start(binary, work + "-data");
    if (!started.ok()) {
      std::fprintf(stderr, "lmd-eval served: %s\n", started.status().message().c_str());
      return 1;
    }
    lmdd.emplace(std::move(started).value());
    target = lmdd->address();
    std::fprintf(stderr, "lmd-eval served: started lmdd on %s (data in %s-data)\n", target.c_str(), work.c_str());
  }
  client::ClientOptions client_options;
  client_options.target = target;
  client_options.deadline = std::chrono::seconds(120);
  Result<std::unique_ptr<client::LmdClient>> client = client::LmdClient::Create(client_options);
  if (!client.ok()) {
    std::fprintf(stderr, "lmd-eval served: %s\n", client.status().message().c_str());
    return 1;
  }

  ServedRun run;
  run.command = "lmd-eval served";
  for (int i = 0; i < argc; ++i) run.command += std::string(" ") + argv[i];
  run.date = Now();
  run.tuned_on = tuned_on;
  const auto start = Clock::now();
  for (const std::string& path : logs) {
    Result<Dataset> d = LoadDataset(path, dataset);
    if (!d.ok()) {
      std::fprintf(stderr, "lmd-eval served: %s\n", d.status().ToString().c_str());
      return 1;
    }
    Result<ServedLog> log = RunLog(**client, *d, options, dataset.seed);
    if (!log.ok()) {
      std::fprintf(stderr, "lmd-eval served: %s\n", log.status().message().c_str());
      return 1;
    }
    const AnswerSummary& s = log->still;
    std::fprintf(stderr, "%s: %zu queries (%zu with a place): place@1 %.3f @5 %.3f, pose %.3f m, sure %.2f right %.4f, "
                 "cpu p50 %.1f p99 %.1f ms", log->name.c_str(), s.queries, s.place_queries, s.place_at_1, s.place_at_5,
                 s.pose_err_m_median, s.localized_share, s.localized_precision, s.cpu_ms_p50, s.cpu_ms_p99);
    if (s.site_count > 0) std::fprintf(stderr, ", site pose %.3f m", s.site_err_m_median);
    if (options.changes) {
      std::fprintf(stderr, "; changes: top mask %.3f, false %.3f", log->changed.change_success_at_1,
                   log->changed.false_mask_share);
    }
    std::fprintf(stderr, "\n");
    run.logs.push_back(std::move(log).value());
  }
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  v1::StatsResponse stats;
  if ((*client)->Stats(v1::StatsRequest(), &stats).ok()) run.lmdd_cpu_seconds = stats.cpu_seconds();
  Status written = WriteServedReport(out_dir, run, options.changes);
  if (!written.ok()) {
    std::fprintf(stderr, "lmd-eval served: %s\n", written.message().c_str());
    return 1;
  }
  std::printf("wrote %s/results.json, report.md, queries.csv, served.svg and calibration.svg (%.0f s)\n",
              out_dir.c_str(), run.seconds);
  return 0;
}

}  // namespace lmd::eval
