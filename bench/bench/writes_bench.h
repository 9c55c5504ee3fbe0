// lmd-bench writes: a stream of inserts into a replicated collection while
// nodes are killed (deploy/test-replication.sh), and the check that nothing
// acknowledged was lost.
//
//   lmd-bench writes --servers A,B,C --collection C --rate R --seconds S --acked FILE
//   lmd-bench writes --verify --servers A,B,C --collection C --acked FILE [--copies N]
//
// Writing: one simulated map per InsertMaps call, R calls per second; lmdd
// assigns the ids, each call has request id "w" + 8 digits and its map the
// write's number as its sequence. A call that fails is sent again (same
// request id: answered once) to the next server, until it is acknowledged;
// each acknowledged map id is appended to FILE with its write's number as it
// is acknowledged. Prints the acknowledged count, the failed attempts, and
// the longest time without an acknowledgement (the failover time when a
// primary was killed).
// Verifying: reads the collection from every server's own copy ("lmd-local"
// metadata: no forwarding) and reports, per server, acknowledged maps
// missing and writes stored more than once (under two ids); exit 1 unless at
// least N copies (default: every server) hold every acknowledged map once.
#pragma once

namespace lmd::bench {

int RunWritesBench(int argc, char** argv);

}  // namespace lmd::bench
