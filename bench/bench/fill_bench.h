// lmd-bench fill: stores N simulated local maps in a running lmdd, in
// batches, with a progress bar; for scale measurements such as lmdd's
// start-up time with 100k maps.
//
//   lmd-bench fill --server HOST:PORT --collection C --maps N [--batch B] [--scans] [--token T]
//
// Maps come from the simulator's streaming generator (building after
// building), B per InsertMaps call (100); without --scans they carry points
// and trajectory only.
#pragma once

namespace lmd::bench {

int RunFillBench(int argc, char** argv);

}  // namespace lmd::bench
