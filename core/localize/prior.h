// Prior queries: a robot that tracks its pose sends it, with its
// uncertainty, in the collection's frame. The anchored maps whose robots
// drove nearest are verified at the pose it implies (a loose prior's until
// they make a sure answer) and, unless the prior is tight or they make one,
// the first stage runs over the anchored maps that can overlap the
// prior region only and its best few are verified too; hits that put the
// query outside the prior are dropped, so that a look-alike elsewhere on the
// site cannot win.
#pragma once

#include <functional>

#include "core/localize/localizer.h"

namespace lmd {

struct Prior {
  Pose2 pose;                      // the query map's own frame in the collection's frame
  double radius_m = 2.0;           // position uncertainty, m (> 0)
  double heading_sigma_rad = 0.35; // heading uncertainty, rad (>= 0)
};

// InvalidArgument naming what is wrong: a non-finite pose, a radius that is
// not positive (or beyond 100 m), a negative or non-finite heading sigma.
Status ValidatePrior(const Prior& prior);

// How the maps nearest `prior` are scan matched: options.match in a window
// of the prior's radius plus prior_margin_m, with no min_score when
// prior_weak_fits.
ScanMatchOptions PriorWindow(const Prior& prior, const LocalizeOptions& options);

// The turn nearest `theta` among those a quarter turn apart from `compass`
// (rad): the entropy compass reads a map's heading modulo 90 deg, so two
// maps' compasses give the turn between them up to quarter turns.
double CompassTurn(double compass, double theta);

// The pose of `query`'s own frame in stored map `db`, anchored at `anchor`,
// that `prior` implies, and the heading window (deg, either side) a search
// from it needs. Its heading is snapped to the turn the two maps' compasses
// give (the heading is known modulo 90 deg to a fraction of a degree) when
// that turn lies within the prior's heading uncertainty widened by
// `window_deg`, and the window stays `window_deg`; else the heading is the
// prior's and the window covers the prior's whole heading range.
Pose2 PriorGuess(const LocalQuery& query, const PreparedMap& db, const Pose2& anchor, const Prior& prior,
                 double window_deg, double* search_window_deg);

// Localises `query` near `prior` among `source`'s anchored maps (the prior
// disk grown by the query's own extent). Each map is searched from the turn
// the maps' compasses give (PriorGuess); where nothing fits within a loose
// prior, the nearest maps again over the prior's whole heading range (a
// compass misreads the turn where walls do not meet at right angles).
// Where the nearest maps leave a robot's answer unsure (loose or tight
// prior), the query is also searched on the site map near the prior
// (site_grid.h).
// Hits carry collection_pose. The
// verdict's rivals are the other maps' disagreeing hits and the best map at
// another pose within the prior window. verdict.prior_failed when no map
// scores options.confidence.min_score there: the robot's prior is wrong (or
// the place is new); it may then ask without a prior.
Localization LocalizeNear(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options,
                          const Prior& prior, const std::function<bool(uint64_t)>& excluded = {},
                          const std::function<bool()>& stop = {}, bool with_changes = false);

}  // namespace lmd
