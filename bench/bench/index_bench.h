// `lmd-bench index`: inverted file vs exhaustive scorer on simulated maps.
#pragma once

namespace lmd::bench {

// argv[0] is the first option after "index". Returns the process exit code.
int RunIndexBench(int argc, char** argv);

}  // namespace lmd::bench
