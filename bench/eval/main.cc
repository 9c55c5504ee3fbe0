// lmd-eval: runs the evaluation protocol of DESIGN.md §4 on laser logs.
#include <cstdio>
#include <string>

#include "bench/eval/commands.h"

namespace {

void Usage(std::FILE* out) {
  std::fprintf(out,
               "usage: lmd-eval <command> [options]\n"
               "commands:\n"
               "  viewpoints [--log FILE...] [--out DIR]\n"
               "      distance (global frame) between the CoG / CoR viewpoints planned in the two maps of\n"
               "      every relevant pair; writes DIR/viewpoints.json (default DIR: out). Without --log:\n"
               "      every *.log.gz of $LMD_DATA_DIR or ../shared/data next to the repository.\n"
               "  render (--log FILE | --demo) [--map INDEX] --out FILE.svg\n"
               "      picture of one local map: grid, walls, rooms, trajectory, CoG and CoR, features.\n"
               "  retrieval [--log FILE...] [--out DIR] [--seed N] [--threads N] [--methods k1,k2] [--ablations]\n"
               "            [--max-queries N]\n"
               "      the paper's experiment (simulated change in every query) for BoW, LMD+CoG, LMD+CoR,\n"
               "      stationary, descriptor settings #1..#8 and best (lmd's best configuration), with\n"
               "      --ablations also best with one option changed per row; writes DIR/results.json,\n"
               "      DIR/report.md and SVG plots (default DIR: out/retrieval). best verifies deeply: all\n"
               "      queries of the nine logs take about 36 min on 2 cores, --max-queries 25 about 3.5 min.\n"
               "  served [--log FILE...] [--out DIR] [--server HOST:PORT | --lmdd PATH] [--seed N]\n"
               "         [--max-queries N] [--threads N] [--verify N] [--tuned-on a,b] [--no-changes]\n"
               "         [--mode global|prior|tracking|sequence] [--anchor] [sensor flags]\n"
               "      the protocol through a live lmdd (started on a temporary store unless --server): every\n"
               "      map inserted, then queried with its 10 m neighbours excluded (Retrieve) and with a\n"
               "      simulated change (DetectChanges); writes DIR/results.json, report.md, queries.csv,\n"
               "      served.svg and calibration.svg (default DIR: out/served). The nine logs take about 3 min\n"
               "      on 2 cores.\n"
               "      --mode prior: each query with its true pose off by 1-3 m and 10-20 deg as a prior\n"
               "      (radius 3.5 m, sigma 20 deg); --mode tracking: off by up to 0.3 m and 2 deg (0.4 m, 3 deg);\n"
               "      --mode sequence: with the 2 maps 5 and 10 m before it and noisy odometry to them (the\n"
               "      maps within 10 m of each excluded);\n"
               "      all three (and --anchor) insert every map with its log pose as pose_hint.\n"
               "  prior-misses [--log FILE...] [--one-pose] [--tracking] [sensor flags]\n"
               "      in process, the --mode prior queries whose top hit misses the place, by why: a map of\n"
               "      the place lmdd did not verify, out-scored by another hit, or matched away from the truth\n"
               "      within the prior's window (--tracking: --mode tracking's priors). About 75 s for the\n"
               "      nine logs on 2 cores.\n"
               "  global-misses [--log FILE...] [--every N] [--anchored] [sensor flags]\n"
               "      in process, the global queries (every Nth) whose top hit misses the place, by why: the\n"
               "      truth scores no higher, or where the first stage and verification lost it; --anchored:\n"
               "      the maps stored anchored at their log poses (a site map). About 2.5 min for the nine\n"
               "      logs on 2 cores, 50 s with --every 3.\n"
               "  change-misses [--log FILE...] [--global] [sensor flags]\n"
               "      in process, the changed queries (--mode tracking's priors; --global: none) whose true\n"
               "      change is not in the first mask, by why: no masks (place not sure nor clear), a mask\n"
               "      below the evidence floor, the change beside a stored point or where no stored map\n"
               "      looked; and the share of false masks. About 70 s (--global 110 s) for the nine logs.\n"
               "  sequence-misses [--log FILE...] [--every N] [--list] [sensor flags]\n"
               "      in process, the --mode sequence queries (every Nth) whose top hit misses the place, by\n"
               "      why: the true pose never proposed, what the robot saw before not stored, or the truth's\n"
               "      sequence fitting no better (--list: each miss with every map's fit).\n"
               "  truth-audit [--log FILE...] [--every N] [--list] [sensor flags]\n"
               "      in process, how much of a hit's pose error is the log's ground truth: maps of one place\n"
               "      matched in loops of three (q in j, q in m, j in m), each match against the log's\n"
               "      relative pose and each loop's closing error, where the log's poses cancel; and the maps\n"
               "      that three or more maps of their place agree to move off their log pose (--list: each).\n"
               "  calibrate --run DIR... [--tuned-on a,b] [--svg FILE]\n"
               "      fits the answer's confidence (ConfidenceOptions::calibration) to the queries.csv of\n"
               "      served runs (the tuning logs' answers of all runs pooled) and prints, per run, how well\n"
               "      the stated and the fitted confidence match how often answers were right, held out\n"
               "      (--svg: the fitted one's reliability diagram, a line per run).\n"
               "  Sensor flags (served, export and the in-process commands): the robots' maps as other robots\n"
               "  would build them; place truth stays the logs'.\n"
               "      --max-range M: the logs read as by a laser that reaches M m (1-30; beyond: no return);\n"
               "      --range-noise S: Gaussian noise of S m added to every return (seeded by --seed);\n"
               "      --fov F: only the beams within F/2 deg of the laser's heading (10-360; 360: all);\n"
               "      --map-drift D: each map built on odometry that drifts within it, up to D deg per metre\n"
               "      and 2 % of length, drawn once per map (0-10; seeded by --seed);\n"
               "      --map-length L: local maps of L m of travel (1-20; the protocol's 5), one every metre.\n"
               "  A --log may be a bag (MCAP, rosbag2 directory or .db3, ROS 1 .bag) with --truth-frame FRAME\n"
               "  (its ground truth in tf, e.g. map) or --truth-odom TOPIC (a nav_msgs/Odometry topic).\n"
               "  export --log FILE... --out DIR [sensor flags]\n"
               "      local maps (own frame points, trajectory) and ground truth as plain text.\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "-h" || command == "--help" || command == "help") {
    Usage(stdout);
    return 0;
  }
  if (command == "viewpoints") return lmd::eval::RunViewpoints(argc - 2, argv + 2);
  if (command == "render") return lmd::eval::RunRender(argc - 2, argv + 2);
  if (command == "retrieval") return lmd::eval::RunRetrieval(argc - 2, argv + 2);
  if (command == "export") return lmd::eval::RunExport(argc - 2, argv + 2);
  if (command == "served") return lmd::eval::RunServed(argc - 2, argv + 2);
  if (command == "prior-misses") return lmd::eval::RunPriorMisses(argc - 2, argv + 2);
  if (command == "change-misses") return lmd::eval::RunChangeMisses(argc - 2, argv + 2);
  if (command == "global-misses") return lmd::eval::RunGlobalMisses(argc - 2, argv + 2);
  if (command == "sequence-misses") return lmd::eval::RunSequenceMisses(argc - 2, argv + 2);
  if (command == "calibrate") return lmd::eval::RunCalibrate(argc - 2, argv + 2);
  if (command == "truth-audit") return lmd::eval::RunTruthAudit(argc - 2, argv + 2);
  std::fprintf(stderr, "lmd-eval: unknown command '%s'\n", command.c_str());
  Usage(stderr);
  return 2;
}
