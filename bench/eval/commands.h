// lmd-eval commands. Each takes argv after the command name and returns the
// process exit code (0 ok, 1 failure, 2 usage error).
#pragma once

namespace lmd::eval {

// lmd-eval viewpoints [--log FILE...] [--out DIR] [--crop M]
int RunViewpoints(int argc, char** argv);
// lmd-eval render (--log FILE --map INDEX | --demo [--map INDEX]) --out FILE.svg
int RunRender(int argc, char** argv);
// lmd-eval retrieval [--log FILE...] [--out DIR] [--seed N] [--threads N] [--methods a,b] [--ablations]
int RunRetrieval(int argc, char** argv);
// lmd-eval export --log FILE... --out DIR
int RunExport(int argc, char** argv);
// lmd-eval served [--log FILE...] [--out DIR] [--server HOST:PORT | --lmdd PATH] [--max-queries N] ...
int RunServed(int argc, char** argv);
// lmd-eval prior-misses [--log FILE...] [--one-pose] [--tracking]
int RunPriorMisses(int argc, char** argv);
// lmd-eval change-misses [--log FILE...] [--global]
int RunChangeMisses(int argc, char** argv);
// lmd-eval global-misses [--log FILE...] [--every N] [--anchored]
int RunGlobalMisses(int argc, char** argv);
// lmd-eval sequence-misses [--log FILE...] [--every N] [--list]
int RunSequenceMisses(int argc, char** argv);
// lmd-eval calibrate --run DIR... [--tuned-on a,b] [--svg FILE]
int RunCalibrate(int argc, char** argv);
// lmd-eval truth-audit [--log FILE...] [--every N] [--list]
int RunTruthAudit(int argc, char** argv);

}  // namespace lmd::eval
