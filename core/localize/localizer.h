// The localisation pipeline: one query map in, ranked stored maps out, each
// with the query's metric pose in it, a verdict on whether the answer can be
// trusted, and the changes the query shows. lmdd's default method and
// lmd-eval's `best` are this code with these defaults.
//
//   1. first stage: the place index (place_index.h) ranks pose hypotheses
//      (map, quarter turn, translation) by feature votes;
//   2. verification: the hypotheses of the first fit_rank_maps maps put
//      in order of the query's fit near each, then the maps of the best
//      (verify_maps) scan matched (core/align: branch and bound in a window
//      around each, ICP), one match per map over all its hypotheses;
//   3. re-ranking by the verification score: the share of query points the
//      map explains, minus the share that lands in its observed free space,
//      minus the share of its points that land in the query's free space;
//   4. the verdict (confidence.h): the best hit's pose refined, then sure
//      when it is strong and neither a hit that disagrees with it nor
//      another pose in the same map comes close;
//   5. change masks (core/change/geometric_changes.h) against the hits that
//      agree with the best one, when the answer is sure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/align/icp.h"
#include "core/align/prepared_map.h"
#include "core/align/scan_match.h"
#include "core/change/change_detector.h"
#include "core/change/geometric_changes.h"
#include "core/localize/confidence.h"
#include "core/localize/map_source.h"
#include "core/place/place_features.h"
#include "core/place/place_index.h"
#include "core/types.h"

namespace lmd {

struct LocalizeOptions {
  PlaceFeatureOptions features;
  PlaceSearchOptions search;
  // Maps scan matched: the best hypotheses' maps, in order of their votes,
  // with all of each map's hypotheses as guesses.
  size_t verify_maps = 20;
  // ... and, in a collection with anchored maps, the best-voted anchored
  // ones the choice left out, each naming a place in the site none of the
  // others names, from all the first stage's hypotheses (the 800 the second
  // round reads, not the first 160), until this many of the verified maps
  // are anchored: where robots store maps without anchors they crowd the
  // choice, and only anchored maps tell identical rooms apart (Judge's
  // one-place rule, sure_needs_site). lmd-bench load, robots asking
  // globally in the simulated building, 150 robots: sure answers with the
  // top hit in a twin room 68 of 3,501 -> 26 of 3,347 (the best-voted 4 of
  // the first 160 hypotheses), lmdd CPU per robot-second the same
  // (docs/results.md, 27th stop). 0: off.
  size_t verify_anchored_maps = 4;
  // A place is verified through few of its maps: a map whose route
  // neighbour (same robot, at most route_window numbers apart) is already
  // among maps_per_route_window chosen ones is passed over, so that the
  // verified maps cover more places (a place the robots passed often
  // collects votes from many maps and would fill every slot, leaving the
  // right place or a rival unverified). 0 = no limit.
  size_t route_window = 4;
  size_t maps_per_route_window = 1;
  // ... in a site map (both maps anchored), only when its hypothesis puts
  // the query within this of a chosen neighbour's guess: a neighbour that
  // names another place is no repeat (its map may show the place where the
  // chosen one's votes named a look-alike stretch). 0: the route alone.
  // Decided on the tuning logs (lmd-eval global-misses --anchored; served
  // --mode sequence), see docs/results.md.
  double route_same_place_m = 2.0;
  // Maps passed over whose chosen neighbours all fit worse than
  // confidence.min_score are verified after all, this many at most.
  size_t passed_over_retries = 5;
  // Before the maps to verify are chosen, the hypotheses of the first
  // fit_rank_maps maps (in vote order) are put in order of how well the
  // query's points fit each map's grid near the hypothesis: the best
  // correlative score at its turn within match.window_m, from blocks of
  // fit_rank_block_m (CorrelativeBound). Votes say which features match;
  // the fit says whether the walls line up, and a corridor's or an
  // office's many alike stretches share votes. 0 maps: vote order.
  // Decided on the tuning logs (lmd-eval global-misses --every 3, aces,
  // fr079, intel, orebro): 47 -> 43 misses of 417 (all hypotheses' maps and
  // 60: 43; 40: 46; blocks 0.2 / 0.8 / 1.6 m: 41 / 45 / 46); held out 291 ->
  // 265 of 1148 (all maps: 258). It reads each of those maps' prepared grids
  // (a cache miss prepares one).
  size_t fit_rank_maps = 60;
  double fit_rank_block_m = 0.4;
  // When no verified map fits (none reaches confidence.min_score), a second
  // round: the first stage's hypotheses, read on to this many, of the maps
  // not verified yet, are all put in order of fit (as fit_rank_maps does,
  // from blocks of second_round_block_m) and the best verify_maps maps
  // verified. A place whose features are few or common (a campus outdoors,
  // a corridor) collects few votes, and its maps rank far down; the fit
  // finds them there, where the query's walls line up. Costs nothing where
  // a map fits. 0: no second round. Decided on the tuning logs (lmd-eval
  // global-misses --every 3, aces, fr079, intel, orebro): 43 -> 37 misses
  // of 417 (1600 hypotheses with 0.4 m blocks: 35, with only their first
  // 200 maps ranked: 37; 800 with 10 maps verified: 38). 1600 / 0.4 m cost frcampus
  // (held out, served) p99 196 ms of lmdd CPU per query against 41 without
  // a second round; 800 / 0.8 m, 94 ms.
  size_t second_round_hypotheses = 800;
  double second_round_block_m = 0.8;
  // Window around each hypothesis; the index's guess already gives the turn.
  ScanMatchOptions match = [] {
    ScanMatchOptions m;
    m.quarter_turns = false;
    return m;
  }();
  // The first `whole_map_maps` maps verified are searched over their whole
  // extent at their hypotheses' turns and the half turns of those (the
  // votes' translation may name a look-alike stretch of the same corridor),
  // instead of near each guess.
  size_t whole_map_maps = 0;
  // The best hit's pose refined by ICP on every query point (verification
  // runs ICP on points icp_cell_m apart).
  bool refine_best = true;
  // The answer's site pose (Verdict::collection_pose) fused from the
  // agreeing anchored maps that fit (FusedSitePose, verification.h) rather
  // than the best map's alone: each map's anchor and match carry their own
  // error, and the maps of a place are independent measurements of it.
  bool fuse_site_pose = true;
  IcpOptions refine = [] {
    IcpOptions icp;
    icp.max_iterations = 30;
    icp.converged_m = 1e-4;
    return icp;
  }();
  // The best hit's pose covariance (Verdict::pose_covariance), from the
  // correspondences `refine` finds.
  PoseCovarianceOptions pose_covariance;
  // The best guess-free alignment of the best hit's map at least
  // self_rival_radius_m (query centroid) or self_rival_angle_deg away from
  // its pose is a rival for the verdict: the same map may fit the query at
  // two poses (a corridor seen from either end). <= 0: not looked for.
  double self_rival_radius_m = 1.0;
  double self_rival_angle_deg = 10.0;
  // Verification score = overlap - conflict_weight * conflicts -
  // reverse_conflict_weight * reverse conflicts (fractions).
  double conflict_weight = 1.0;
  double reverse_conflict_weight = 1.0;
  // Verified hits are ranked by the score with this weight of the overlap's
  // share within inlier_radius_m replaced by its closeness
  // (Overlap::closeness, icp.h: how near the explained points lie). A
  // look-alike corridor or room brings about as many query points within
  // 0.3 m as the place does, but less close: its doors, recesses and wall
  // offsets differ by a decimetre or two. The share stays in the blend, as
  // how much of the query a map shows is what makes it a map of the place.
  // The score itself is unchanged (the protocol's 0.3 m), so the verdict's
  // thresholds keep their meaning: a best hit whose score is below a
  // disagreeing hit's has no margin and is not sure. 0: by the score.
  // Decided on the tuning logs (aces, fr079, intel, orebro), served, against
  // ranking by the score (0): 1 (closeness alone) lost aces 3 global
  // queries' places (place@1 .753 -> .740); 0.5 lost none on any log. Served
  // (2026-12-06, docs/results.md): global place@1 held out .864 -> .870
  // (mit .631 -> .656), sure and wrong 17 -> 15. Not within a prior
  // (LocalizeNear ranks by the score): there the maps show one place, and
  // closeness picked maps that explain part of the query closely at a pose a
  // few decimetres off (lmd-bench load --mode fleet, 200 robots: sure and
  // wrong 1 -> 6, all under 1 m off, right fixes .999 -> .996; served
  // tracking and loose priors: the same place@1, sure and wrong 46 -> 43
  // and 41 -> 42). A sequence's hypotheses are ranked alike, by the mean of
  // their maps' blended fits (sequence.h): lmd-eval sequence-misses --every
  // 3, 155 -> 147 misses (tuning logs 27 -> 26; 1 instead of 0.5: 147);
  // served --mode sequence place@1 .924 -> .928, none sure and wrong.
  double closeness_weight = 0.5;
  ConfidenceOptions confidence;
  // The evidence floor (geometric_changes.h): 1.5 where the place's maps
  // explain the rest of the query, 1.5 more for every 1 % of its points that
  // are change points outside the mask. Chosen on aces, fr079, intel and
  // orebro (every mask of lmd-eval change-misses dumped, tracking priors and
  // global queries; floors 1-3.5, doubling shares 0.67-4 %): the most true
  // changes in the top mask at no more false masks than the fixed floor of 5
  // it replaced (which kept 0.79 of the masks that found the change on those
  // logs and 0.09 of the others). Served, with changes, 2026-12-06, every
  // other answer the same: global, top mask held out .441 -> .495 (tuned on
  // .366 -> .446), false masks held out 7.1 -> 4.7 % (tuned on 7.0 -> 5.6
  // %); --mode tracking, held out .564 -> .615 (tuned on .539 -> .614),
  // false masks held out 6.6 -> 4.8 % (tuned on 7.2 -> 6.8 %).
  GeometricChangeOptions changes = [] {
    GeometricChangeOptions c;
    c.min_evidence = 1.5;
    c.floor_doubling_share = 0.01;
    return c;
  }();
  // Change masks also for an answer that is not sure but whose place is
  // clear (Conclude in localizer.cc): the best hit reaches
  // confidence.min_score and no disagreeing hit comes within
  // confidence.min_margin of it. No threshold of its own. Served (lmd-eval
  // served, global queries with and without a change, one lmdd, back to
  // back, 2026-12-05): true change in the top mask held out .331 -> .400,
  // tuned on .251 -> .352; false masks held out 4.7 -> 5.7 %, tuned on 6.7
  // -> 5.8 %; lmdd CPU per changed query 13.5 -> 13.8 ms median. Masks for
  // every answer whose best hit fits (the margin not asked): .488 held out,
  // but 14.8 % false (mit 49.7 %: look-alikes).
  bool changes_where_place_clear = true;
  // ... and for a robot's prior query (loose or tight), where its best hit
  // fits, whatever the margin: the prior rules the look-alikes out itself
  // (as it does for the verdict's min_confidence), so a rival within the
  // margin is another pose of the place, not another place. No threshold of
  // its own. Served (lmd-eval served, with changes, 2026-12-06, all answers
  // the same otherwise): --mode tracking, true change in the top mask .515
  // -> .553 (held out .526 -> .564), false masks 7.1 -> 6.9 % (held out 6.9
  // -> 6.6 %); --mode prior .498 -> .553 (held out .507 -> .561), false
  // masks 6.7 -> 7.1 % (held out 6.6 -> 6.4 %; fr079, tuned on, 5.7 ->
  // 11.5 %). A best hit at 0.5 instead of min_score: tracking .633 at 8.5 %
  // false, 0.4: .663 at 12.1 %.
  bool prior_changes_without_margin = true;
  // Whether an answer's place fits, for change masks, is asked of the maps
  // agreeing with its best hit together, the maps the masks are made
  // against (PlaceFit, verification.h), where the best hit alone falls below
  // confidence.min_score: a place the robot saw whole and the stored maps
  // each saw in part fits as a place, though no one map does. A global
  // answer still needs its best hit's margin. No threshold of its own;
  // decided on all nine logs. Served (lmd-eval served, with changes,
  // 2026-12-06, back to back; every other answer the same): global, true
  // change in the top mask held out .405 -> .441 (tuned on .352 -> .366),
  // false masks held out 5.7 -> 7.1 % (tuned on 5.8 -> 7.0 %). A prior's
  // answer too since the fifteenth stop (2026-12-06): the false alarms that
  // had kept it out (--mode tracking, edmonton 1.0 -> 17.9 %) were masks on
  // the change, counted false because their maps each showed less than half
  // the query (lmd-eval's mask rule before ef573ea). Served, with changes,
  // back to back: --mode tracking, top mask tuned on .649 -> .690 (held out
  // .665 -> .722), false masks tuned on 7.6 -> 7.8 % (held out 6.2 -> 6.8
  // %); --mode prior, .637 -> .674 (.644 -> .705), false 7.8 -> 8.3 % (7.1
  // -> 7.6 %).
  bool changes_place_fit_of_union = true;
  // Whether the place fits, for change masks, is also asked of the best
  // hit's overlap (the share of the query its map explains), not only of
  // its score, which subtracts the query's points in the map's free space:
  // those are what a change is, so a large change would lower the fit
  // below min_score and hide itself. No threshold of its own (min_score).
  // A sequence's hits keep their score (the mean fit of its maps).
  // Served, with changes, 2026-12-06, every other answer the same:
  // --mode tracking, true change in the top mask held out .615 -> .668
  // (tuned on .614 -> .654), false masks held out 4.8 -> 5.9 % (tuned on
  // 6.8 -> 6.7 %); global, held out .495 -> .499 (tuned on .446 -> .448),
  // false 4.7 -> 4.9 % (5.6 -> 5.6 %). An overlap of 0.5 (the place-recall
  // protocol's share) instead: tracking .719, but 7.8 % false (frcampus
  // 15.0 %).
  bool changes_place_fit_before_conflicts = true;
  // An answer in an anchored collection (a site map), whatever its query,
  // makes its change masks against its place's maps and also against this
  // many anchored maps whose robots drove nearest the query's path at the
  // answer's site pose, each where its anchor puts it (no scan match): what
  // the site saw free or occupied there, not only what the maps matched to
  // the query saw. More of the change's points lie where some stored map
  // saw free space, and more of a spurious mask's points are explained by
  // one. Chosen on aces, fr079, intel and orebro (lmd-eval change-misses,
  // tracking priors: true change in the top mask 922 of their 1,245 tasks
  // with none, 943 with 4 or 8; 4 reads fewer maps). Served, with changes,
  // back to back (2026-12-06): --mode tracking, top mask tuned on .690 ->
  // .710, held out .722 -> .742, false masks tuned on 7.8 -> 7.5 %, held
  // out 6.8 -> 5.9 %; --mode prior .674 -> .696 and .705 -> .728, false
  // 8.3 -> 9.1 % and 7.6 -> 7.8 %; --mode sequence (80 per log) .332 ->
  // .352 and .366 -> .398, false 14.1 -> 10.9 % and 3.4 -> 6.0 %. Global
  // answers in a site map (lmd-eval change-misses --global, in process):
  // 2,056 -> 2,129 of 4,698 tasks, false 5.7 -> 5.6 %. 0: none.
  size_t changes_site_maps = 4;
  // A query of fewer points is never sure nor gets masks: a point or two fit
  // somewhere in any stored map and pin no pose (a single point scored 1.0,
  // sure, against orebro's maps; found by a bad-input audit). Not fitted:
  // below every real local map of the nine logs (after the 0.1 m
  // deduplication: 145-344 points at the least per log, one map of frcampus
  // 34), so no measured answer changes. Points on one line are left to the
  // rival search, which finds their other fits.
  size_t min_sure_points = 30;
  // A global answer is sure only when its map got at least this many more
  // first-stage votes than any map the search did not look at
  // (LocalizeStats::unexamined_votes): verification sees only the maps the
  // votes name, and where the votes do not single the answer's map out, a
  // map never looked at may fit as well (a twin room elsewhere on a large
  // site). Its place may still be clear for change masks (PlaceClear):
  // keeping such answers from masks too cost the held-out logs 0.499 ->
  // 0.474 of their true changes in the top mask for no fewer false masks
  // (4.8 -> 4.9 %). Votes are counts (the default vote_temperature 0), and
  // a lead one vote can undo is none: 2.
  // Chosen on the simulated 100k-map site (lmd-bench places --maps 100000
  // --queries 1000): sure answers 917 at 97.2 % right without a lead, 898
  // at 98.4 % with 1, 855 at 99.6 % with 2, 818 at 100 % with 3. Its cost
  // on the nine real logs (lmd-eval served --no-changes, looked at after):
  // held-out sure share 0.352 -> 0.350 / 0.341 / 0.331, no answer made
  // right or wrong. 0: no lead needed.
  double sure_vote_lead = 2;
  // In a collection with anchored maps, an answer is sure only where its
  // anchored hits name its place in the site (SitePlaceClear): an anchored
  // map that agrees with the best leads the anchored maps elsewhere and its
  // own map's other pose as a sure answer's best must. Maps stored without
  // anchors that agree may show identical rooms at two places (they put no
  // wall in each other's free space), and only anchors tell them apart; a
  // twin room's anchored map may agree too, and fit better where it saw more
  // of the room. A collection without anchors has no site to place an
  // answer in, and is not affected; one anchored map makes it a site. Where
  // the best hit is anchored, Judge's margin already asks this. lmd-bench
  // load, robots asking globally in the simulated building of repeated
  // rooms, 40 s (docs/results.md, 28th stop): sure answers with the top hit
  // elsewhere or the site pose off, 40 robots 30 of 741 -> 0 of 270, 150
  // robots 84 of 3,030 -> 6 of 1,035 (a second pair: 100 of 3,341 -> 4 of
  // 1,034). No threshold of its own.
  bool sure_needs_site = true;
  size_t top_k = 10;  // hits returned (and the hit giving the site pose, where it ranks past them)
  // Prior queries (prior.h): anchored maps matched, nearest the predicted
  // query first, and the window beyond the prior's radius; with
  // prior_first_stage, as many again from the first stage over the maps near
  // the prior (a sequence's check of where a hypothesis puts each map skips it).
  // 6 instead of 4: served (lmd-eval served --mode prior --no-changes), tuning
  // logs (aces, fr079, intel, orebro) place@1 .963 -> .966, sure and wrong
  // 23 -> 17, lmdd CPU +8 %; 8 gave .971 but 20 wrong at +25 % CPU. Held out
  // after: .940 -> .943 (8: .946), 39 -> 40 wrong, CPU +4 %. A loose
  // prior verifies them best-bounded first and stops once those verified
  // make a sure answer that two more agreeing maps that fit confirm
  // (prior.cc, kConfirmingMaps). A tight prior verifies all its
  // tight_prior_maps: with the stop, --mode tracking's sure answers were
  // right 99.93 -> 99.82 % (at 5.3 -> 3.9 ms of lmdd CPU).
  size_t prior_maps = 6;
  double prior_margin_m = 1.0;
  bool prior_first_stage = true;
  // A prior that is not tight: each of the nearest maps verified is searched
  // again for its best pose away from the one found (self_rival_radius_m,
  // self_rival_angle_deg) and the better one kept. No threshold of its own.
  // Served (lmd-eval served --mode prior --no-changes, 2026-12-04, back to
  // back): place@1 held out .944 -> .955, tuned on .967 -> .978, sure and
  // wrong 59 -> 58 of about 3,130, lmdd CPU 8.1 -> 10.8 ms median. Found
  // with lmd-eval prior-misses on all nine logs. A sequence's check of where
  // a hypothesis puts each map skips it. Only where the nearest maps' first
  // poses leave the answer unsure: where they make it sure, a best shifted
  // so is still caught as a rival (the verdict searches the best map's other
  // poses), though another map's better shifted pose is not looked for.
  // Served, all queries back to back (2026-12-08): lmdd CPU held out 15.3 ->
  // 9.8 ms median; place@1 and sure answers' precision the same (.991, 2
  // wrong), sure .477 -> .478; 60 of 5,678 answers differ. Only sure
  // answers get cheaper: the p99 (unsure loose priors) read 117.8 -> 101.6
  // ms in that pair and did not fall in two later ones (docs/results.md).
  bool prior_second_pose = true;
  // A robot's prior (loose or tight; not a sequence's check), where its
  // nearest maps leave the answer unsure: the query is also searched once on
  // the site map near the prior (the anchored maps there fused into one
  // grid, site_grid.h), and the prior_site_maps maps that explain most of it
  // at the site's best pose are verified there. 0: not searched. No
  // threshold of its own. Found with lmd-eval prior-misses (nine logs, in
  // process): loose priors 96 -> 79 misses (frcampus 49 -> 36; its
  // "shifted" class, a map's search preferring a corridor shifted along
  // itself, 44 -> 33), tracking priors (--tracking) 109 -> 56 (frcampus
  // 67 -> 39, mit 28 -> 11). Served (lmd-eval served --no-changes,
  // 2026-12-05, one lmdd, back to back): --mode prior place@1 .9893 ->
  // .9902 (held out .9884 -> .9911, tuned on .9903 -> .9891), sure and
  // wrong 44 -> 41, lmdd CPU 9.8 -> 11.9 ms median; --mode tracking .985 ->
  // .992 (held out .980 -> .990), sure .658 -> .668, sure and wrong 38 ->
  // 46 (each new one the right place at the truth's edge: 0.20-0.38 m or
  // 1.07-1.13 deg off, seven fitting the query better than the log's pose),
  // 4.0 -> 5.1 ms. Searched for every loose prior instead: the same
  // place@1, 45 wrong, 19.2 ms median.
  size_t prior_site_maps = 3;
  // A prior that is not tight runs the first stage only when the nearest
  // maps' hits do not already make a sure answer: the stage finds the place
  // where the nearest maps do not show it; where they do, the verdict's
  // search of the best map's other poses looks for a rival within the
  // prior's window. No threshold of its own (the verdict's). Served
  // (lmd-eval served --mode prior --no-changes, 2026-12-05, back to back):
  // place@1 .982 either way (held out .978), sure .632 -> .635, sure and
  // wrong 53 -> 50 (tuning logs 20 -> 19, held out 33 -> 31), lmdd CPU
  // median 13.0 -> 9.6 ms (held out 13.6 -> 9.9), p99 46.7 -> 44.0 ms.
  bool prior_stage_when_unsure = true;
  // The maps nearest a prior are searched for their best pose in its window
  // however weak it is, not only above the search's min_score (the mean
  // likelihood a search without a prior asks for): the prior says they can
  // show the query, a map that shows half of it falls short of that mean,
  // and verification judges the fit. Found on edmonton's misses (held out,
  // looked at). Served, back to back (2026-12-04): --mode prior place@1
  // held out .955 -> .972, tuned on .978 -> .978, sure and wrong 58 -> 58,
  // lmdd CPU 10.0 -> 12.1 ms median; --mode tracking held out .966 -> .980,
  // 47 -> 47 wrong, 4.1 -> 4.4 ms. A sequence's check keeps min_score:
  // there a weak fit of an earlier map props up a wrong hypothesis (place@1
  // .887 -> .882 with it).
  bool prior_weak_fits = true;
  // A loose prior's sure answer also faces its best map's best other
  // optimum beyond this distance (query centroid), within the prior's window:
  // a pose that fits about as well 0.2-1 m away breaks what a sure answer
  // promises (0.2 m), and the self-rival above looks only beyond 1 m. Not
  // fitted: the promise's radius; a match that ICP brings back within it is
  // the same optimum. Served (lmd-eval served --mode prior --no-changes,
  // 2026-12-05, back to back): no answer changes; sure and wrong 51 -> 44
  // (tuning logs 17 -> 15, held out 34 -> 29; four of the seven 0.7-2.9 m
  // off, three at the truth's 0.2 m edge), sure 0.647 -> 0.642 (23 right
  // answers unsure), lmdd CPU the same. Not for tight priors (--mode
  // tracking: 31 right answers unsure for 2 wrong ones at the truth's edge)
  // nor global answers (5 right unsure for 2 at the edge, +15 % CPU).
  double prior_near_rival_m = 0.2;
  // Where no map fits within a prior that is not tight (nothing reaches
  // confidence.min_score inside it), the best-bounded prior_maps of all the
  // anchored maps near the prior that were not verified yet are verified
  // too. The maps whose robots drove nearest show a place from the usual
  // spots; outdoors a map made tens of metres away can be the one that
  // shows it. Found on frcampus (held out, looked at): of its 29
  // lmd-eval prior-misses with an unverified map of the place that fits,
  // that map was among the 24 nearest by path for 5, and among all the
  // 180-680 maps near the prior first by the bound for 10, within the
  // first 6 for 19. No threshold of its own. Served (lmd-eval served
  // --mode prior --no-changes, back to back, 2026-12-05): place@1 .986 ->
  // .989 (held out .985 -> .988, tuned on .988 -> .990), sure and wrong 48
  // -> 51 (3 of the 4 new ones fit the query better than the log's pose),
  // lmdd CPU 9.8 / 57.0 -> 10.3 / 68.5 ms median / p99. A sequence's check
  // skips it (its windows are the odometry's, and they often fit nothing).
  bool prior_any_near_maps = true;
  // ... bounding at most this many of them, the newest (10 us a map): where
  // a fleet piles up maps, the maps near a prior run into thousands. On the
  // nine logs of ../shared/data it changes no answer (frcampus's misses had
  // 180-680 maps near their priors).
  size_t prior_any_near_max_maps = 1000;
  // A tight prior (radius and heading sigma at most these), as a tracking
  // robot sends after a fix, skips the first stage (with prior_first_stage
  // on) and has the tight_prior_maps best-bounded of the 4 x as many maps
  // nearest it verified instead. Why: the radius is half the first stage's
  // 1 m vote cell, the sigma the scan matcher's own +-3 deg window, so the
  // stage's hypotheses add little about where the query is, and the maps
  // whose robots drove nearest show the query's view. It trades a little
  // recall for CPU and fewer sure and wrong answers. Measured in process on
  // the tuning logs (aces, fr079, intel, orebro; every other map queried, 10
  // m neighbours excluded, priors off by <= 0.3 m and <= 2 deg, radius 0.4
  // m, sigma 3 deg), stage always -> this: place@1 .974 / .986 / .996 /
  // 1.000 -> .991 / .990 / .992 / .982, sure and wrong 11 -> 7, CPU per
  // query 6.2 / 11.8 / 6.7 / 4.9 -> 3.5 / 7.3 / 2.9 / 2.7 ms. Skipping the
  // stage with 4 maps verified: .974 / .967 / .984 / 1.000 at 2.6 / 4.1 /
  // 2.4 / 1.7 ms. Served: docs/results.md, "Tracking priors".
  double tight_prior_radius_m = 0.5;
  double tight_prior_sigma_deg = 3.0;
  size_t tight_prior_maps = 8;
  // Sequence queries (sequence.h): hypotheses of the newest map checked
  // against the earlier maps; odometry drift allowed per metre travelled
  // (position, m/m; heading, rad/m) on top of the scan matching window.
  size_t sequence_hypotheses = 8;
  size_t sequence_prior_maps = 2;  // anchored maps matched per earlier map and hypothesis
  // ... and for the newest map, whose hit there is the answer's: the two
  // maps whose robots drove nearest often are not the ones that show its
  // view (a map of the place fitting 0.57 not among them, the hit reported
  // one that does not show the place at 0.24). lmd-eval sequence-misses,
  // tuning logs (aces, fr079, intel, orebro), every other map: 45 -> 34
  // misses of 604 (12 maps: 33; 4 per earlier map as well: 33); held out
  // (the other five), every third map: 135 -> 128 of 990. With 6 hypotheses
  // instead of 8 the tuning logs keep 34 but held out gives 132 (4: 133).
  // Served (--mode sequence --no-changes --max-queries 80, back to back):
  // place@1 .905 -> .922 (held out .930 -> .935), sure .392 -> .408, none
  // wrong, lmdd CPU 51.7 -> 58.9 ms median.
  size_t sequence_newest_maps = 6;
  // A sequence answer that is not sure, though an earlier map fits at its
  // best hypothesis (sequence_agreeing >= 1), gives way to the newest map
  // judged alone (over its own hits and its fits at every hypothesis, as a
  // global answer is judged) where that is sure at the same place. Served
  // (--mode sequence --no-changes --max-queries 250, nine logs, back to
  // back): sure 0.332 -> 0.354 of the answers, none wrong. Without the
  // confirming earlier map, 1 of 45 new sure answers was wrong (held-out
  // edmonton, 0.31 m off, fitting better than the log's pose): the
  // condition was added after seeing it (docs/results.md, 27th stop).
  bool sequence_newest_alone = true;
  double sequence_drift = 0.03;
  double sequence_drift_rad_per_m = 0.02;
};

// What the pipeline computes once per stored map (lmdd: at insert): the map
// prepared for scan matching, with its free space, and its place features in
// the compass frame of map->heading.
struct PreparedPlace {
  std::shared_ptr<const PreparedMap> map;
  PlaceFeatures features;
};
PreparedPlace PreparePlace(const LocalMap& map, const LocalizeOptions& options);

// The query side, prepared once.
struct LocalQuery {
  std::shared_ptr<const PreparedMap> map;  // the query as a map (points, free space, heading)
  PlaceFeatures features;                  // in map->heading's compass frame
  PreparedQuery match;                     // subsampled points for scan matching
  LocalMap source;                         // points, trajectory and scans (change masks)
};

// Prepares `map` (own frame). `prepared`: the same map's PreparePlace
// (e.g. it was stored a moment ago); null: computed here.
LocalQuery PrepareLocalQuery(LocalMap map, const LocalizeOptions& options, const PreparedPlace* prepared = nullptr);

struct LocalizedHit {
  uint64_t map_id = 0;
  Pose2 pose;                    // query own frame in the db map's own frame
  double score = 0.0;            // verification score (above)
  double overlap = 0.0;          // share of query points within the inlier radius
  double conflict = 0.0;         // share of query points in the db map's free space
  double reverse_conflict = 0.0; // share of db points in the query's free space
  double inlier_rms_m = 0.0;     // RMS distance of the explained query points (ties: smaller first)
  double closeness = 0.0;        // Overlap::closeness (icp.h): how near the explained query points lie
  double votes = 0.0;            // first-stage votes of its map's most voted hypothesis
  size_t first_stage_rank = 0;   // rank of the hypothesis it was verified from, in the order verification chose (0 = first)
  bool agrees_with_best = false; // a place hit: consistent with the best hit (confidence.h)
  std::optional<Pose2> collection_pose;  // the query's own frame in the collection's frame (anchored maps)
  size_t sequence_agreeing = 0;  // sequence queries: earlier maps that fit this hypothesis
  std::shared_ptr<const PreparedMap> db;
};

struct LocalizeStats {
  size_t hypotheses = 0;     // from the first stage
  size_t maps_matched = 0;   // scan matches run
  size_t second_poses = 0;   // of them, a prior's nearest maps searched again away from their first pose
  PlaceSearchStats search;
  double search_ms = 0, verify_ms = 0, verdict_ms = 0, changes_ms = 0;
  // The most first-stage votes of a map the global search neither fit
  // ranked nor verified (one cut from its hypotheses counts with the last
  // one kept); 0 where none was left (or no global search ran).
  double unexamined_votes = 0;
};

struct Localization {
  std::vector<LocalizedHit> hits;  // best first, top_k at most, then the hit giving the site pose if it ranks past them
  Verdict verdict;
  std::vector<ChangeMask> changes;  // best first; db_map_id = a hit's map id
  LocalizeStats stats;
};

// Runs the pipeline on `source`'s maps, leaving out those `excluded` says.
// `stop` (optional) is asked before each scan match; once true, no further
// map is matched. `with_changes`: compute change masks.
Localization Localize(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options,
                      const std::function<bool(uint64_t)>& excluded = {}, const std::function<bool()>& stop = {},
                      bool with_changes = false);

}  // namespace lmd
