// lmd-bench index --maps N [--queries Q] [--json] [--seed S] [--threads T]
//                 [--top-k K] [--max-offset M] [--method lmd|bow]
//                 [--max-word-share F] [--setting S] [--bits B] [--inner M] [--cache FILE]
// Builds an index of N simulated local maps (simulator -> planner ->
// describer), runs Q queries through the inverted file and the exhaustive
// scorer in the same process, and reports p50 latencies, their ratio, whether
// every top-K agreed (ids, scores, orientations, offsets, ranks) and bytes per
// stored map (encoded Lmd + posting records). With --json the last stdout line
// is {"maps": N, "indexed_ms_p50": x, "exhaustive_ms_p50": y, "top10_agree": b,
// "bytes_per_map": z}. --setting, --bits and --inner (inner words' radius, m,
// with WithInnerWords' feature cap; 0 = none) choose the descriptor (default:
// the product's, ProductDescriberOptions: #6 with 13-bit words). Progress
// goes to stderr. --cache FILE keeps the described maps and queries (encoded
// Lmds) so that runs with other retrieval options skip the simulator and the
// describer (reused only if N, Q, the seed, the setting, the bits and the inner radius match).
#include "bench/bench/index_bench.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <time.h>

#include "bench/bench/sim_descriptors.h"
#include "bench/common/flags.h"
#include "core/describe/describer.h"
#include "core/describe/lmd_codec.h"
#include "core/index/exhaustive.h"
#include "core/index/index.h"
#include "core/index/postings.h"
#include "core/util/progress_bar.h"

namespace lmd::bench {
namespace {

struct Args {
  size_t maps = 1000;
  size_t queries = 50;
  bool json = false;
  uint64_t seed = 1;
  int threads = 0;
  int setting = 6;  // the paper's descriptor setting #1..#8 (product default: #6)
  int bits = 13;    // appearance word bits B (product default: 13)
  double inner_m = 0.0;  // inner words' radius (m, WithInnerWords' feature cap), 0 = none
  std::string cache;
  RetrieveOptions retrieve;
};

void Usage() {
  std::fprintf(stderr,
               "usage: lmd-bench index --maps N [--queries Q] [--json] [--seed S] [--threads T]\n"
               "                       [--top-k K] [--max-offset M] [--method lmd|bow]\n"
               "                       [--max-word-share F] [--setting 1..8] [--bits B] [--inner M]\n"
               "                       [--cache FILE]\n");
}

bool ParseArgs(int argc, char** argv, Args* args) {
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "--help") == 0) {
      Usage();
      std::exit(0);
    }
  }
  Flags flags({"maps", "queries", "seed", "threads", "top-k", "max-offset", "max-word-share", "setting", "bits",
               "inner", "cache", "method"},
              {"json"});
  uint64_t maps = 0, queries = 0, threads = 0, top_k = 0, setting = 0, bits = 0;
  const bool ok = flags.Parse(argc, argv) && flags.Count("maps", 1, 10000000, args->maps, &maps) &&
                  flags.Count("queries", 1, 100000, args->queries, &queries) &&
                  flags.Count("seed", 0, UINT64_MAX, args->seed, &args->seed) &&
                  flags.Count("threads", 1, 256, 0, &threads) &&
                  flags.Count("top-k", 1, 1000000, args->retrieve.top_k, &top_k) &&
                  flags.Number("max-offset", 0, 100, args->retrieve.max_offset_m, &args->retrieve.max_offset_m) &&
                  flags.Number("max-word-share", 1e-6, 1, args->retrieve.max_word_share, &args->retrieve.max_word_share) &&
                  flags.Count("setting", 1, 8, static_cast<uint64_t>(args->setting), &setting) &&
                  flags.Count("bits", 1, 16, static_cast<uint64_t>(args->bits), &bits) &&
                  flags.Number("inner", 0, 12, args->inner_m, &args->inner_m);
  if (!ok) {
    std::fprintf(stderr, "lmd-bench index: %s\n", flags.error().c_str());
    Usage();
    return false;
  }
  args->maps = maps, args->queries = queries, args->retrieve.top_k = top_k;
  args->threads = static_cast<int>(threads);  // 0: every core
  args->setting = static_cast<int>(setting), args->bits = static_cast<int>(bits);
  args->json = flags.Has("json");
  args->cache = flags.Get("cache");
  const std::string method = flags.Get("method", "lmd");
  if (method != "lmd" && method != "bow") {
    std::fprintf(stderr, "lmd-bench index: --method must be lmd or bow, got '%s'\n", method.c_str());
    return false;
  }
  args->retrieve.method = method == "lmd" ? Method::kLmd : Method::kBow;
  return true;
}

// Cache file: "lmdbench3" N Q seed setting bits inner-radius-mm, then per set (maps, queries)
// its count and per Lmd a length and its EncodeLmd bytes, then the query
// sources; every number a native-order u64.
void PutU64(std::ofstream& out, uint64_t v) { out.write(reinterpret_cast<const char*>(&v), sizeof(v)); }
bool GetU64(std::ifstream& in, uint64_t* v) { return static_cast<bool>(in.read(reinterpret_cast<char*>(v), sizeof(*v))); }

uint64_t InnerMm(const Args& args) { return static_cast<uint64_t>(std::llround(args.inner_m * 1000)); }

bool LoadCache(const std::string& path, const Args& args, SimDescriptors* data) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char magic[9] = {};
  uint64_t n = 0, q = 0, seed = 0, setting = 0, bits = 0, inner_mm = 0;
  if (!in.read(magic, 9) || std::memcmp(magic, "lmdbench3", 9) != 0 || !GetU64(in, &n) || !GetU64(in, &q) ||
      !GetU64(in, &seed) || !GetU64(in, &setting) || !GetU64(in, &bits) || !GetU64(in, &inner_mm) ||
      n != args.maps || q != args.queries || seed != args.seed || setting != static_cast<uint64_t>(args.setting) ||
      bits != static_cast<uint64_t>(args.bits) || inner_mm != InnerMm(args))
    return false;
  auto read_lmds = [&](uint64_t count, std::vector<Lmd>* out) {
    for (uint64_t k = 0; k < count; ++k) {
      uint64_t len = 0;
      if (!GetU64(in, &len) || len > (1u << 24)) return false;
      std::string bytes(len, '\0');
      if (!in.read(bytes.data(), static_cast<std::streamsize>(len))) return false;
      auto lmd = DecodeLmd(bytes);
      if (!lmd.ok()) return false;
      out->push_back(std::move(lmd).value());
    }
    return true;
  };
  uint64_t stored_maps = 0, stored_queries = 0;
  if (!GetU64(in, &stored_maps) || !read_lmds(stored_maps, &data->maps) || !GetU64(in, &stored_queries) ||
      !read_lmds(stored_queries, &data->queries))
    return false;
  for (uint64_t k = 0; k < stored_queries; ++k) {
    uint64_t source = 0;
    if (!GetU64(in, &source)) return false;
    data->query_sources.push_back(source);
  }
  return true;
}

void SaveCache(const std::string& path, const Args& args, const SimDescriptors& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write("lmdbench3", 9);
  PutU64(out, args.maps);
  PutU64(out, args.queries);
  PutU64(out, args.seed);
  PutU64(out, static_cast<uint64_t>(args.setting));
  PutU64(out, static_cast<uint64_t>(args.bits));
  PutU64(out, InnerMm(args));
  for (const std::vector<Lmd>* set : {&data.maps, &data.queries}) {
    PutU64(out, set->size());
    for (const Lmd& lmd : *set) {
      const std::string bytes = EncodeLmd(lmd);
      PutU64(out, bytes.size());
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
  }
  for (uint64_t source : data.query_sources) PutU64(out, source);
  if (!out) std::fprintf(stderr, "lmd-bench index: could not write the cache %s\n", path.c_str());
}

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// CPU time of this thread, ms (robust when other processes share the cores).
double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

bool SameHits(const std::vector<MapHit>& a, const std::vector<MapHit>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].map_id != b[i].map_id || a[i].score != b[i].score || a[i].orientation != b[i].orientation ||
        a[i].offset.x != b[i].offset.x || a[i].offset.y != b[i].offset.y || a[i].rank != b[i].rank)
      return false;
  }
  return true;
}

}  // namespace

int RunIndexBench(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, &args)) return 2;
  if (args.threads == 0) args.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  // 1. Descriptors of simulated local maps.
  SimDescriptorOptions sim;
  sim.maps = args.maps;
  sim.queries = args.queries;
  sim.seed = args.seed;
  sim.threads = args.threads;
  sim.describer = ProductDescriberOptions();
  sim.describer.setting = PaperDescriptorSetting(args.setting);
  sim.describer.word_bits = args.bits;
  if (args.inner_m > 0) {
    sim.describer = WithInnerWords(sim.describer);
    sim.describer.inner_radius_m = args.inner_m;
  }
  SimDescriptors data;
  const bool cached = !args.cache.empty() && LoadCache(args.cache, args, &data);
  if (cached) {
    std::fprintf(stderr, "lmd-bench index: %zu maps and %zu queries from the cache %s\n", data.maps.size(),
                 data.queries.size(), args.cache.c_str());
  } else {
    data = SimDescriptors();
    ProgressBar bar("simulate + describe maps", args.maps);
    data = SimulateDescriptors(sim, [&](size_t done, size_t) { bar.Update(done); });
    bar.Done();
    if (!args.cache.empty()) SaveCache(args.cache, args, data);
  }
  if (data.maps.size() < args.maps)
    std::fprintf(stderr, "lmd-bench index: the simulator gave %zu maps of %zu\n", data.maps.size(), args.maps);

  // 2. Index, encoded sizes.
  auto created = Index::Create();
  if (!created.ok()) return 1;
  Index index = std::move(created).value();
  size_t lmd_bytes = 0, posting_bytes = 0, features = 0;
  const auto add_start = std::chrono::steady_clock::now();
  double add_ms = 0;
  {
    ProgressBar bar("index maps", data.maps.size());
    for (size_t n = 0; n < data.maps.size(); ++n) {
      const Lmd& lmd = data.maps[n];
      lmd_bytes += EncodeLmd(lmd).size();
      auto records = PostingsOf(n, lmd, index.options());
      if (!records.ok()) {
        std::fprintf(stderr, "lmd-bench index: map %zu: %s\n", n, records.status().ToString().c_str());
        return 1;
      }
      posting_bytes += PostingBytes(*records);
      features += lmd.features.size();
      const auto t0 = std::chrono::steady_clock::now();
      Status st = index.Add(n, lmd);
      add_ms += Ms(t0, std::chrono::steady_clock::now());
      if (!st.ok()) {
        std::fprintf(stderr, "lmd-bench index: map %zu: %s\n", n, st.ToString().c_str());
        return 1;
      }
      if (n % 1024 == 0) bar.Update(n);
    }
    bar.Done();
  }
  (void)add_start;
  const double nmaps = static_cast<double>(std::max<size_t>(1, data.maps.size()));
  // Word statistics: how skewed the appearance words are decides how much any
  // inverted file can prune (a word on every map matches every map).
  std::map<uint32_t, size_t> word_counts;
  for (const Lmd& lmd : data.maps)
    for (const Feature& f : lmd.features) ++word_counts[f.appearance_word];
  size_t top_word = 0;
  double sum_p2 = 0;
  for (const auto& kv : word_counts) {
    top_word = std::max(top_word, kv.second);
    const double p = static_cast<double>(kv.second) / static_cast<double>(std::max<size_t>(1, features));
    sum_p2 += p * p;
  }

  // 3. Queries: inverted file and exhaustive scorer, same queries, same process.
  std::vector<double> inverted_ms, exhaustive_ms, inverted_cpu, exhaustive_cpu, touched, scored, postings;
  size_t agree = 0, source_found = 0;
  (void)index.Retrieve(data.queries.empty() ? Lmd() : data.queries[0], args.retrieve);  // warm-up
  {
    ProgressBar bar("queries", data.queries.size());
    for (size_t q = 0; q < data.queries.size(); ++q) {
      RetrieveStats stats;
      const double c0 = ThreadCpuMs();
      const auto t0 = std::chrono::steady_clock::now();
      auto inverted = index.Retrieve(data.queries[q], args.retrieve, &stats);
      const auto t1 = std::chrono::steady_clock::now();
      const double c1 = ThreadCpuMs();
      auto exhaustive = RetrieveExhaustive(index, data.queries[q], args.retrieve);
      const auto t2 = std::chrono::steady_clock::now();
      const double c2 = ThreadCpuMs();
      inverted_cpu.push_back(c1 - c0);
      exhaustive_cpu.push_back(c2 - c1);
      if (!inverted.ok() || !exhaustive.ok()) {
        std::fprintf(stderr, "lmd-bench index: query %zu failed\n", q);
        return 1;
      }
      inverted_ms.push_back(Ms(t0, t1));
      exhaustive_ms.push_back(Ms(t1, t2));
      touched.push_back(static_cast<double>(stats.maps_touched));
      scored.push_back(static_cast<double>(stats.maps_scored));
      postings.push_back(static_cast<double>(stats.postings_read));
      agree += SameHits(*inverted, *exhaustive);
      for (const MapHit& h : *inverted) source_found += h.map_id == data.query_sources[q];
      bar.Update(q + 1);
    }
    bar.Done();
  }
  const double inv_p50 = Percentile(inverted_ms, 0.5), exh_p50 = Percentile(exhaustive_ms, 0.5);
  const bool all_agree = agree == data.queries.size();
  const double bytes_per_map = static_cast<double>(lmd_bytes + posting_bytes) / nmaps;

  std::printf("lmd-bench index: %zu maps (seed %llu), descriptor #%d, %d-bit words, %zu queries, top-%zu, method %s, "
              "max offset %.2f m\n",
              data.maps.size(), static_cast<unsigned long long>(args.seed), args.setting, args.bits, data.queries.size(),
              args.retrieve.top_k, args.retrieve.method == Method::kLmd ? "lmd" : "bow",
              args.retrieve.max_offset_m);
  if (cached) {
    std::printf("  build: maps described by an earlier run (cache), index add %.2f s\n", add_ms / 1000.0);
  } else {
    std::printf("  build: simulate %.1f s, plan + describe %.1f s (%d threads, %.2f ms/map), index add %.2f s\n",
                data.simulate_s, data.describe_s, args.threads, 1000.0 * data.describe_s / nmaps, add_ms / 1000.0);
  }
  if (args.retrieve.max_word_share < 1.0)
    std::printf("  stop list               %zu words above %.3f of all features\n",
                index.StopWords(args.retrieve.max_word_share).size(), args.retrieve.max_word_share);
  std::printf("  features per map        %.1f\n", static_cast<double>(features) / nmaps);
  std::printf("  appearance words        %zu distinct, most frequent %.1f%% of features, "
              "%.0f same-word feature pairs per pair of maps\n",
              word_counts.size(), 100.0 * static_cast<double>(top_word) / static_cast<double>(std::max<size_t>(1, features)),
              sum_p2 * (static_cast<double>(features) / nmaps) * (static_cast<double>(features) / nmaps));
  std::printf("  bytes per stored map    %.0f (encoded Lmd %.0f + posting records %.0f)\n", bytes_per_map,
              static_cast<double>(lmd_bytes) / nmaps, static_cast<double>(posting_bytes) / nmaps);
  std::printf("  index memory per map    %.0f bytes (%zu postings)\n",
              static_cast<double>(index.MemoryBytes()) / nmaps, index.PostingCount());
  const double inv_cpu = Percentile(inverted_cpu, 0.5), exh_cpu = Percentile(exhaustive_cpu, 0.5);
  std::printf("  query latency           p50 ms    p90 ms    p50 cpu ms\n");
  std::printf("    inverted file         %8.3f  %8.3f  %8.3f\n", inv_p50, Percentile(inverted_ms, 0.9), inv_cpu);
  std::printf("    exhaustive scorer     %8.3f  %8.3f  %8.3f\n", exh_p50, Percentile(exhaustive_ms, 0.9), exh_cpu);
  std::printf("  speed-up (p50)          %.1fx wall, %.1fx cpu\n", inv_p50 > 0 ? exh_p50 / inv_p50 : 0.0,
              inv_cpu > 0 ? exh_cpu / inv_cpu : 0.0);
  std::printf("  top-%zu identical        %s (%zu of %zu queries)\n", args.retrieve.top_k,
              all_agree ? "yes" : "NO", agree, data.queries.size());
  std::printf("  per query (p50)         %.0f postings read (%.1f%% of all), %.0f maps touched, %.0f scored exactly\n",
              Percentile(postings, 0.5),
              100.0 * Percentile(postings, 0.5) / static_cast<double>(std::max<size_t>(1, index.PostingCount())),
              Percentile(touched, 0.5), Percentile(scored, 0.5));
  std::printf("  re-observed map in top-%zu: %zu of %zu queries\n", args.retrieve.top_k, source_found,
              data.queries.size());
  if (args.json) {
    std::printf("{\"maps\": %zu, \"indexed_ms_p50\": %.4f, \"exhaustive_ms_p50\": %.4f, \"top10_agree\": %s, "
                "\"bytes_per_map\": %.1f}\n",
                data.maps.size(), inv_p50, exh_p50, all_agree ? "true" : "false", bytes_per_map);
  }
  return all_agree ? 0 : 1;
}

}  // namespace lmd::bench
