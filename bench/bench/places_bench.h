// `lmd-bench places`: the localisation pipeline (core/localize) at scale on
// simulated maps: N stored maps kept as lmdd keeps them (place features in
// a PlaceIndex in memory, the maps themselves aside and prepared for scan
// matching on demand through a bounded LRU cache), Q re-observed maps as
// queries, CPU per query of the first stage and of the whole Localize, and
// whether the answers are right. docs/places_bench.md has the figures.
#pragma once

namespace lmd::bench {

// argv[0] is the first option after "places". Returns the process exit code
// (0 on success, 2 on bad arguments, 1 when the run could not be made).
int RunPlacesBench(int argc, char** argv);

}  // namespace lmd::bench
