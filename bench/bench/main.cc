// lmd-bench: index scale and load benchmarks.
#include <cstdio>
#include <string>

#include "bench/bench/fill_bench.h"
#include "bench/bench/index_bench.h"
#include "bench/bench/load_bench.h"
#include "bench/bench/places_bench.h"
#include "bench/bench/reads_bench.h"
#include "bench/bench/writes_bench.h"

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "index") return lmd::bench::RunIndexBench(argc - 2, argv + 2);
  if (command == "load") return lmd::bench::RunLoadBench(argc - 2, argv + 2);
  if (command == "fill") return lmd::bench::RunFillBench(argc - 2, argv + 2);
  if (command == "places") return lmd::bench::RunPlacesBench(argc - 2, argv + 2);
  if (command == "writes") return lmd::bench::RunWritesBench(argc - 2, argv + 2);
  if (command == "reads") return lmd::bench::RunReadsBench(argc - 2, argv + 2);
  if (command.empty() || command == "-h" || command == "--help") {
    std::printf("usage: lmd-bench <command> [options]\n"
                "commands:\n"
                "  index --maps N [--queries Q] [--json]   inverted file vs exhaustive scorer on simulated maps\n"
                "  load --server HOST:PORT --collection C --robots R --hz H --seconds S [--json]\n"
                "       [--no-seed] [--first-robot N]      simulated robots inserting and detecting changes\n"
                "       [--log CARMEN_LOG]                 (--log: robots driving a real log's maps again)\n"
                "       [--mode fleet]                     robots tracking with priors from drifting odometry\n"
                "       [--answers FILE]                   each DetectChanges as answered (TSV)\n"
                "  fill --server HOST:PORT --collection C --maps N [--batch B] [--scans]\n"
                "                                          store N simulated maps (scale runs)\n"
                "  places --maps N [--queries Q] [--json]  localisation pipeline on N simulated maps (scale)\n"
                "  writes --servers A,B,C --collection C --rate R --seconds S --acked FILE\n"
                "       [--verify [--copies N]]            inserts through node failures; check nothing acknowledged is lost\n"
                "  reads --servers A[,B,...] --collection C [--threads T] [--seconds S]\n"
                "                                          query throughput, the queries spread over the servers\n");
    return command.empty() ? 2 : 0;
  }
  std::fprintf(stderr, "lmd-bench: unknown command '%s' (try --help)\n", command.c_str());
  return 2;
}
