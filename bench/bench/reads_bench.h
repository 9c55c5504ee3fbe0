// lmd-bench reads: query throughput of a collection, the queries spread over
// the servers given (deploy/test-replication.sh compares one copy with
// three: reads are served by any in-sync copy).
//
//   lmd-bench reads --servers A[,B,...] --collection C [--threads T] [--seconds S]
//
// The queries are up to 100 of the collection's own stored maps (read from
// the first server), each sent as a default-method Retrieve with itself
// excluded; T threads send them back to back, each call to the next server
// in turn. Prints queries per second, latency p50 / p99 and errors.
#pragma once

namespace lmd::bench {

int RunReadsBench(int argc, char** argv);

}  // namespace lmd::bench
