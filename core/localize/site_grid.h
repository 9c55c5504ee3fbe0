// A robot's prior query matched against the site map near the prior: the
// points of the anchored maps there, fused into one search grid in the
// collection's frame, searched once over the prior's window. Where a place
// is split over several stored maps (a robot saw part of it on each pass),
// no one of them fits the query as the site does, and a corridor shifted
// along one map can out-fit its true pose there but not on the site, whose
// maps reach on past the map's ends. The maps that explain most of the
// query at the site's pose then give the hits. Internal to core/localize
// (prior.cc).
#pragma once

#include <functional>
#include <vector>

#include "core/localize/prior.h"

namespace lmd::localize_internal {

// Up to options.prior_site_maps hits: the anchored maps near `prior` (those
// `excluded` names left out) that explain most of the query at the pose
// that fits the fused site grid best, each scan matched just around it.
// The site is searched at the turns the maps' compasses give within the
// prior's heading range (each +-options.match.window_deg), or over the
// whole range when none lies in it. Nothing once options' stop says so
// (StopAsked, verification.h).
std::vector<LocalizedHit> SiteGridHits(const LocalQuery& query, const MapSource& source,
                                       const LocalizeOptions& options, const Prior& prior,
                                       const std::function<bool(uint64_t)>& excluded, LocalizeStats* stats);

}  // namespace lmd::localize_internal
