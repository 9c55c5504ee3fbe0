// Anchored collections over gRPC: maps inserted with a pose hint are
// anchored, prior queries search near the robot's estimate and answer in the
// collection's frame, sequence queries check a lost robot's earlier maps, a
// sure answer anchors the map inserted next, and bad priors or sequences are
// refused without changing anything stored.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"
#include "proto/convert.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

// The stored demo maps: every third of the first 150, anchored by their
// simulated global frame (as a robot with SLAM would give them).
constexpr size_t kStored = 150, kStride = 3;

v1::InsertMapRequest AnchoredInsert(const LocalMap& map, size_t sequence) {
  v1::InsertMapRequest insert = OneMapRequest("site", map.id, ToProto(map)).maps(0);
  insert.mutable_metadata()->set_robot_id("robot-1");
  insert.mutable_metadata()->set_sequence(sequence);
  *insert.mutable_metadata()->mutable_pose_hint() = ToProto(map.truth.global_frame);
  return insert;
}

class AnchoredQueryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<TestServer>(dir_.path());
    v1::InsertMapsRequest request;
    for (size_t i = 0; i < kStored; i += kStride) *request.add_maps() = AnchoredInsert(DemoMaps()[i], i + 1);
    v1::InsertMapsResponse inserted;
    ASSERT_TRUE(server_->client().InsertMaps(request, &inserted).ok());
  }

  // A query of stored map `i` seen again: the same points, nothing excluded
  // but the map itself.
  v1::RetrieveRequest Query(size_t i) const {
    v1::RetrieveRequest request;
    request.set_collection("site");
    *request.mutable_map() = ToProto(DemoMaps()[i + 1]);  // the next window: overlaps map i, not stored
    return request;
  }

  // Demo map `newest` with the maps 5 and 10 before it as its sequence
  // (exact odometry).
  v1::RetrieveRequest SequenceQuery(size_t newest) const {
    v1::RetrieveRequest request = Query(newest - 1);
    for (size_t back : {5, 10}) {
      v1::SequenceMap* step = request.add_sequence();
      const LocalMap& earlier = DemoMaps()[newest - back];
      *step->mutable_map() = ToProto(earlier);
      *step->mutable_in_query() =
          ToProto(Compose(Inverse(DemoMaps()[newest].truth.global_frame), earlier.truth.global_frame));
      step->set_travel_m(static_cast<double>(back));
    }
    return request;
  }

  // Query(i) with a prior at `pose` (heading sigma 0: unset).
  v1::RetrieveRequest PriorRequest(size_t i, const Pose2& pose, double radius_m, double sigma_rad = 0.0) const {
    v1::RetrieveRequest request = Query(i);
    *request.mutable_prior()->mutable_pose() = ToProto(pose);
    request.mutable_prior()->set_radius_m(radius_m);
    if (sigma_rad > 0) request.mutable_prior()->set_heading_sigma_rad(sigma_rad);
    return request;
  }

  // Query(i) with a prior at `pose`, radius 2 m.
  v1::RetrieveResponse PriorQuery(size_t i, const Pose2& pose) const {
    const v1::RetrieveRequest request = PriorRequest(i, pose, 2.0);
    v1::RetrieveResponse response;
    EXPECT_TRUE(server_->client().Retrieve(request, &response).ok());
    return response;
  }

  uint64_t StoredMaps() const {
    v1::ListCollectionsResponse listed;
    EXPECT_TRUE(server_->client().ListCollections(&listed).ok());
    for (const v1::CollectionInfo& c : listed.collections()) {
      if (c.name() == "site") return c.maps();
    }
    return 0;
  }

  TempDir dir_;
  std::unique_ptr<TestServer> server_;
};

double Distance(const v1::Pose2& a, const Pose2& b) { return std::hypot(a.x() - b.x, a.y() - b.y); }

TEST_F(AnchoredQueryTest, APoseHintAnchorsTheMapAndHitsCarryTheCollectionPose) {
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id(DemoMaps()[0].id);
  v1::GetMapResponse got;
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  ASSERT_TRUE(got.map().metadata().has_anchor());
  EXPECT_FALSE(got.map().metadata().anchor().derived());
  EXPECT_LT(Distance(got.map().metadata().anchor().pose(), DemoMaps()[0].truth.global_frame), 1e-3);

  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(Query(30), &response).ok());
  ASSERT_GT(response.hits_size(), 0);
  ASSERT_TRUE(response.hits(0).has_collection_pose());
  // The query's own frame in the collection's frame: its simulated global frame.
  EXPECT_LT(Distance(response.hits(0).collection_pose(), DemoMaps()[31].truth.global_frame), 0.1);
  // The answer's site pose: the first hit's, named by its map.
  ASSERT_TRUE(response.localization().has_collection_pose());
  EXPECT_LT(Distance(response.localization().collection_pose(), FromProto(response.hits(0).collection_pose())), 1e-9);
  EXPECT_EQ(response.localization().collection_pose_map_id(), response.hits(0).map_id());
  // With the pose, how closely it is known: in the hit's frame and the
  // collection's, turned (the same variances in x and y together, the same
  // in heading), and within centimetres where the demo's rooms pin it.
  ASSERT_TRUE(response.localization().has_pose_covariance());
  ASSERT_TRUE(response.localization().has_collection_pose_covariance());
  const v1::PoseCovariance& hit = response.localization().pose_covariance();
  const v1::PoseCovariance& site = response.localization().collection_pose_covariance();
  EXPECT_GT(hit.xx(), 0.0);
  EXPECT_GT(hit.tt(), 0.0);
  EXPECT_NEAR(hit.xx() + hit.yy(), site.xx() + site.yy(), 1e-12);
  EXPECT_DOUBLE_EQ(hit.tt(), site.tt());
  EXPECT_LT(std::sqrt(hit.xx() + hit.yy()), 0.2);
}

TEST_F(AnchoredQueryTest, APriorNearTheTruthLocalisesInTheCollectionsFrame) {
  int localized = 0, asked = 0;
  for (size_t i = 12; i < kStored - 3; i += 21) {
    const Pose2 truth = DemoMaps()[i + 1].truth.global_frame;
    const v1::RetrieveRequest request = PriorRequest(i, {truth.x + 1.5, truth.y - 1.0, truth.theta + 0.25}, 3.0, 0.3);
    v1::RetrieveResponse response;
    ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
    ++asked;
    EXPECT_TRUE(response.localization().prior_used());
    EXPECT_FALSE(response.localization().prior_failed()) << i;
    ASSERT_GT(response.hits_size(), 0);
    if (response.localization().localized()) {  // a sure answer must be right, and its pose pinned
      EXPECT_LT(Distance(response.hits(0).collection_pose(), truth), 0.2) << i;
      EXPECT_GE(response.localization().slide_margin(), 0.1) << i;
      ++localized;
    }
  }
  EXPECT_GE(localized, asked - 2);  // the demo world repeats rooms: a few may stay unsure
}

// The maps a prior query excludes (by map id) are passed over where the
// store picks the maps near the prior, and the maps beyond them answer.
TEST_F(AnchoredQueryTest, APriorQueryPassesOverTheMapsItExcludes) {
  for (size_t i = 30; i < kStored - 3; i += 45) {
    const Pose2 truth = DemoMaps()[i + 1].truth.global_frame;
    v1::RetrieveRequest request = PriorRequest(i, {truth.x + 0.5, truth.y, truth.theta}, 1.0, 0.05);
    v1::RetrieveResponse first;
    ASSERT_TRUE(server_->client().Retrieve(request, &first).ok());
    ASSERT_GT(first.hits_size(), 0) << i;
    for (const v1::MapHit& hit : first.hits()) request.add_exclude_map_ids(hit.map_id());
    v1::RetrieveResponse second;
    ASSERT_TRUE(server_->client().Retrieve(request, &second).ok());
    EXPECT_GT(second.hits_size(), 0) << i;
    for (const v1::MapHit& hit : second.hits()) {
      for (const v1::MapHit& excluded : first.hits()) EXPECT_NE(hit.map_id(), excluded.map_id()) << i;
    }
  }
}

TEST_F(AnchoredQueryTest, AWrongPriorSaysSoAndMayFallBackToAGlobalQuery) {
  const Pose2 truth = DemoMaps()[31].truth.global_frame;
  v1::RetrieveRequest request = Query(30);
  *request.mutable_prior()->mutable_pose() = ToProto(Pose2{truth.x + 300.0, truth.y + 300.0, truth.theta});
  request.mutable_prior()->set_radius_m(2.0);
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  EXPECT_TRUE(response.localization().prior_failed());
  EXPECT_FALSE(response.localization().localized());
  EXPECT_EQ(response.hits_size(), 0);

  request.mutable_prior()->set_fall_back_to_global(true);
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  EXPECT_TRUE(response.localization().prior_failed());
  EXPECT_TRUE(response.localization().fell_back_to_global());
  ASSERT_GT(response.hits_size(), 0);
  EXPECT_LT(Distance(response.hits(0).collection_pose(), truth), 0.1);
}

TEST_F(AnchoredQueryTest, ASequenceQuerySaysHowManyOfItsMapsAgree) {
  const size_t newest = 61;
  v1::RetrieveRequest request = SequenceQuery(newest);
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  EXPECT_EQ(response.localization().sequence_maps(), 2u);
  ASSERT_GT(response.hits_size(), 0);
  EXPECT_LT(Distance(response.hits(0).collection_pose(), DemoMaps()[newest].truth.global_frame), 0.1);
  EXPECT_EQ(response.localization().sequence_agreeing(), response.hits(0).sequence_agreeing());
  EXPECT_GE(response.hits(0).sequence_agreeing(), 1u);
}

// A robot that drove through a yard no stored map shows sends a map that
// fits nowhere; the mean fit of its sequence then falls short. Where its
// other earlier map fits, the newest map judged alone answers, sure at the
// sequence's best place, and the response says so (with the vote lead of a
// global answer, where its search left maps unexamined).
TEST_F(AnchoredQueryTest, ASequenceLeftShortByAnUnmappedPlaceIsAnsweredByItsNewestMap) {
  LocalMap yard;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-6.0, 6.0);
  for (int i = 0; i < 600; ++i) yard.points.push_back({coordinate(rng), coordinate(rng)});
  size_t by_newest = 0;
  for (size_t newest : {31, 61, 91, 121}) {
    v1::RetrieveRequest request = SequenceQuery(newest);
    *request.mutable_sequence(1)->mutable_map() = ToProto(yard);
    v1::RetrieveResponse response;
    ASSERT_TRUE(server_->client().Retrieve(request, &response).ok()) << newest;
    const v1::Localization& verdict = response.localization();
    if (!verdict.sequence_by_newest()) {
      EXPECT_FALSE(verdict.has_vote_lead()) << newest;  // an anchored sequence's own answer
      continue;
    }
    ++by_newest;
    EXPECT_TRUE(verdict.localized()) << newest;
    EXPECT_EQ(verdict.sequence_maps(), 2u) << newest;
    EXPECT_GE(verdict.sequence_agreeing(), 1u) << newest;
    if (verdict.has_vote_lead()) EXPECT_GE(verdict.vote_lead(), 2.0) << newest;
    ASSERT_TRUE(verdict.has_collection_pose()) << newest;
    EXPECT_LT(Distance(verdict.collection_pose(), DemoMaps()[newest].truth.global_frame), 0.2) << newest;
  }
  EXPECT_GE(by_newest, 2u);
}

// Lost robots store maps without anchors; where they crowd a place, a
// sequence query still answers in the site frame: only anchored maps can
// give it a site pose, and only they are searched.
TEST_F(AnchoredQueryTest, ASequenceQueryAnswersInTheSiteFrameWhereUnanchoredMapsCrowd) {
  const size_t newest = 61;
  v1::InsertMapsRequest crowd;
  for (size_t copy = 0; copy < 3; ++copy) {
    for (size_t i = newest - 1; i <= newest + 1; ++i) {
      *crowd.add_maps() = OneMapRequest("site", "lost-" + std::to_string(copy) + "-" + std::to_string(i),
                                        ToProto(DemoMaps()[i])).maps(0);
    }
  }
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(crowd, &inserted).ok());
  v1::RetrieveRequest request = SequenceQuery(newest);
  request.set_verify_candidates(3);  // as many as the crowd's copies of the query's own map
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  ASSERT_GT(response.hits_size(), 0);
  ASSERT_TRUE(response.localization().has_collection_pose());
  EXPECT_LT(Distance(response.localization().collection_pose(), DemoMaps()[newest].truth.global_frame), 0.1);
  EXPECT_EQ(response.localization().collection_pose_map_id().rfind("lost-", 0), std::string::npos);
  // A plain query of the same map is answered from every map: the crowd's
  // exact copy of it first.
  v1::RetrieveRequest plain_request = Query(newest - 1);
  plain_request.set_verify_candidates(3);
  v1::RetrieveResponse plain;
  ASSERT_TRUE(server_->client().Retrieve(plain_request, &plain).ok());
  ASSERT_GT(plain.hits_size(), 0);
  EXPECT_EQ(plain.hits(0).map_id().rfind("lost-", 0), 0u) << plain.hits(0).map_id();
}

// Where maps without anchors crowd a place, a global answer's best hit has
// no anchor: the anchored hit that gives its site pose is returned after the
// hits asked for, and a sure answer in a site always has that pose.
TEST_F(AnchoredQueryTest, AGlobalAnswerNamesItsSitePoseHitPastTopK) {
  const size_t q = 61;
  v1::InsertMapsRequest crowd;
  for (size_t copy = 0; copy < 3; ++copy) {
    *crowd.add_maps() =
        OneMapRequest("site", "lost-" + std::to_string(copy), ToProto(DemoMaps()[q])).maps(0);
  }
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(crowd, &inserted).ok());
  v1::RetrieveRequest request = Query(q - 1);  // map q itself, seen again
  request.set_top_k(1);
  v1::RetrieveResponse response;
  ASSERT_TRUE(server_->client().Retrieve(request, &response).ok());
  ASSERT_EQ(response.hits_size(), 2);
  EXPECT_EQ(response.hits(0).map_id().rfind("lost-", 0), 0u) << response.hits(0).map_id();
  const v1::Localization& verdict = response.localization();
  ASSERT_TRUE(verdict.has_collection_pose());
  EXPECT_EQ(verdict.collection_pose_map_id(), response.hits(1).map_id());
  EXPECT_EQ(verdict.collection_pose_map_id().rfind("lost-", 0), std::string::npos);
  EXPECT_LT(Distance(verdict.collection_pose(), DemoMaps()[q].truth.global_frame), 0.1);
}

TEST_F(AnchoredQueryTest, ASureAnswerAnchorsTheMapInsertedNext) {
  const LocalMap& map = DemoMaps()[46];  // not stored; overlaps stored map 45
  v1::DetectChangesRequest detect;
  detect.set_collection("site");
  *detect.mutable_map() = ToProto(map);
  v1::DetectChangesResponse detected;
  ASSERT_TRUE(server_->client().DetectChanges(detect, &detected).ok());
  ASSERT_TRUE(detected.localization().localized());

  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("site", "new", ToProto(map)), &inserted).ok());
  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id("new");
  v1::GetMapResponse got;
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  const v1::MapMetadata& meta = got.map().metadata();
  ASSERT_TRUE(meta.has_anchor());
  EXPECT_TRUE(meta.anchor().derived());
  EXPECT_EQ(meta.anchor().from_map_id(), detected.hits(0).hit().map_id());
  EXPECT_GT(meta.anchor().confidence(), 0.5);
  EXPECT_LT(Distance(meta.anchor().pose(), map.truth.global_frame), 0.1);

  // A sure answer against that derived anchor does not anchor the next map:
  // an error would otherwise carry on from map to map.
  const LocalMap& next = DemoMaps()[47];
  detect.clear_exclude_map_ids();
  for (size_t i = 0; i < kStored; i += kStride) detect.add_exclude_map_ids(DemoMaps()[i].id);  // all but "new"
  *detect.mutable_map() = ToProto(next);
  ASSERT_TRUE(server_->client().DetectChanges(detect, &detected).ok());
  ASSERT_GT(detected.hits_size(), 0);
  EXPECT_EQ(detected.hits(0).hit().map_id(), "new");
  ASSERT_TRUE(detected.localization().localized());
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("site", "next", ToProto(next)), &inserted).ok());
  get.set_map_id("next");
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  EXPECT_FALSE(got.map().metadata().has_anchor());

  // A map no query localised is stored without an anchor.
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("site", "plain", ToProto(DemoMaps()[200])), &inserted).ok());
  get.set_map_id("plain");
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  EXPECT_FALSE(got.map().metadata().has_anchor());
}

TEST_F(AnchoredQueryTest, BadPriorsAndSequencesAreRefusedAndNothingChanges) {
  const uint64_t before = StoredMaps();
  auto code_of = [&](const v1::RetrieveRequest& request, const std::string& says) {
    v1::RetrieveResponse response;
    const grpc::Status status = server_->client().Retrieve(request, &response);
    EXPECT_NE(status.error_message().find(says), std::string::npos) << status.error_message();
    return status.error_code();
  };
  v1::RetrieveRequest nan_prior = Query(30);
  nan_prior.mutable_prior()->mutable_pose()->set_x(NAN);
  nan_prior.mutable_prior()->set_radius_m(2.0);
  EXPECT_EQ(code_of(nan_prior, "prior.pose.x"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest negative = Query(30);
  negative.mutable_prior()->set_radius_m(-1.0);
  EXPECT_EQ(code_of(negative, "prior.radius_m"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest both = Query(30);
  both.mutable_prior()->set_radius_m(2.0);
  *both.add_sequence()->mutable_map() = ToProto(DemoMaps()[20]);
  EXPECT_EQ(code_of(both, "not both"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest no_pose = Query(30);
  *no_pose.add_sequence()->mutable_map() = ToProto(DemoMaps()[20]);
  EXPECT_EQ(code_of(no_pose, "sequence[0].in_query"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest ragged = Query(30);
  v1::SequenceMap* step = ragged.add_sequence();
  *step->mutable_map() = ToProto(DemoMaps()[20]);
  step->mutable_map()->add_x(1.0f);  // one x more than y
  step->mutable_in_query();
  EXPECT_EQ(code_of(ragged, "sequence[0].map"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest long_sequence = Query(30);
  for (int i = 0; i < 9; ++i) {
    v1::SequenceMap* s = long_sequence.add_sequence();
    *s->mutable_map() = ToProto(DemoMaps()[20]);
    s->mutable_in_query();
  }
  EXPECT_EQ(code_of(long_sequence, "max_sequence_maps"), grpc::StatusCode::INVALID_ARGUMENT);

  v1::RetrieveRequest paper = Query(30);
  paper.set_method(v1::METHOD_LMD_COG);
  paper.mutable_prior()->set_radius_m(2.0);
  EXPECT_EQ(code_of(paper, "default method"), grpc::StatusCode::INVALID_ARGUMENT);

  // A collection without anchored maps cannot take a prior.
  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("bare", "a", SquareRoomMap()), &inserted).ok());
  v1::RetrieveRequest bare = Query(30);
  bare.set_collection("bare");
  bare.mutable_prior()->set_radius_m(2.0);
  EXPECT_EQ(code_of(bare, "no anchored maps"), grpc::StatusCode::FAILED_PRECONDITION);

  EXPECT_EQ(StoredMaps(), before);
}

TEST_F(AnchoredQueryTest, AnchorsSurviveARestart) {
  server_->Stop();
  server_ = std::make_unique<TestServer>(dir_.path());
  const Pose2 truth = DemoMaps()[31].truth.global_frame;
  const v1::RetrieveResponse response = PriorQuery(30, Pose2{truth.x + 1.0, truth.y, truth.theta});
  EXPECT_FALSE(response.localization().prior_failed());
  ASSERT_GT(response.hits_size(), 0);
  EXPECT_LT(Distance(response.hits(0).collection_pose(), truth), 0.1);
}

// A better estimate of where the site lies (the whole site moved by a rigid
// transform, as a SLAM loop closure might): lmdctl anchor sets the stored
// maps' anchors anew, and prior queries follow them.
TEST_F(AnchoredQueryTest, ReanchoredMapsMoveTheSiteAndPriorQueriesFollow) {
  const Pose2 moved{100.0, -50.0, M_PI / 2};
  std::ofstream anchors(dir_.path() + "/anchors.txt");
  anchors << "# id x y theta_deg\n";
  for (size_t i = 0; i < kStored; i += kStride) {
    const Pose2 a = Compose(moved, DemoMaps()[i].truth.global_frame);
    anchors << DemoMaps()[i].id << " " << a.x << " " << a.y << " " << a.theta * 180.0 / M_PI << "\n";
  }
  anchors.close();
  const uint64_t before = StoredMaps();
  const std::string base = "--server " + server_->address() + " ";
  const CliRun run = RunLmdctl(base + "anchor --collection site --file " + dir_.path() + "/anchors.txt", dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("re-anchored 50 maps of 'site'"), std::string::npos) << run.out;
  EXPECT_EQ(StoredMaps(), before);  // replaced, not added

  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id(DemoMaps()[30].id);
  v1::GetMapResponse got;
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  ASSERT_TRUE(got.map().metadata().has_anchor());
  EXPECT_FALSE(got.map().metadata().anchor().derived());
  EXPECT_LT(Distance(got.map().metadata().anchor().pose(), Compose(moved, DemoMaps()[30].truth.global_frame)), 1e-3);
  EXPECT_EQ(got.map().metadata().robot_id(), "robot-1");  // the rest of the metadata is kept
  EXPECT_EQ(got.map().metadata().sequence(), 31u);
  // --json: the map as stored, one line, its anchor among its metadata.
  const Pose2 again = Compose(moved, DemoMaps()[30].truth.global_frame);
  const CliRun json = RunLmdctl(base + "--json anchor --collection site --id " + DemoMaps()[30].id + " --pose " +
                                    std::to_string(again.x) + "," + std::to_string(again.y) + "," +
                                    std::to_string(again.theta * 180.0 / M_PI), dir_);
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_EQ(json.out.rfind("{\"id\":\"" + DemoMaps()[30].id + "\"", 0), 0u) << json.out;
  EXPECT_NE(json.out.find("\"anchor\":{\"pose\":{"), std::string::npos) << json.out;
  EXPECT_EQ(std::count(json.out.begin(), json.out.end(), '\n'), 1);

  const Pose2 truth = Compose(moved, DemoMaps()[31].truth.global_frame);
  const v1::RetrieveResponse response = PriorQuery(30, Pose2{truth.x + 1.0, truth.y, truth.theta});
  EXPECT_FALSE(response.localization().prior_failed());
  ASSERT_GT(response.hits_size(), 0);
  EXPECT_LT(Distance(response.hits(0).collection_pose(), truth), 0.1);
  // Where the site was before, nothing is anchored any more.
  const Pose2 old = DemoMaps()[31].truth.global_frame;
  EXPECT_TRUE(PriorQuery(30, Pose2{old.x + 1.0, old.y, old.theta}).localization().prior_failed());
}

TEST_F(AnchoredQueryTest, AnAnchorForAnUnknownMapOrABadPoseChangesNothing) {
  const std::string base = "--server " + server_->address() + " ";
  std::ofstream(dir_.path() + "/missing.txt") << DemoMaps()[0].id << " 1 2 3\nno-such-map 4 5 6\n";
  CliRun run = RunLmdctl(base + "anchor --collection site --file " + dir_.path() + "/missing.txt", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("NOT_FOUND"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("missing.txt:2; nothing re-anchored"), std::string::npos) << run.err;
  std::ofstream(dir_.path() + "/twice.txt") << DemoMaps()[0].id << " 1 2 3\n" << DemoMaps()[0].id << " 4 5 6\n";
  run = RunLmdctl(base + "anchor --collection site --file " + dir_.path() + "/twice.txt", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("twice.txt:2: map " + DemoMaps()[0].id + " is anchored already at"), std::string::npos)
      << run.err;
  run = RunLmdctl(base + "anchor --collection site --id " + DemoMaps()[0].id + " --pose 1,nan,3", dir_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--pose must be X,Y,THETA"), std::string::npos) << run.err;
  run = RunLmdctl(base + "anchor --collection site --id " + DemoMaps()[0].id + " --pose 1e300,0,0", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("INVALID_ARGUMENT"), std::string::npos) << run.err;

  v1::GetMapRequest get;
  get.set_collection("site");
  get.set_map_id(DemoMaps()[0].id);
  v1::GetMapResponse got;
  ASSERT_TRUE(server_->client().GetMap(get, &got).ok());
  EXPECT_LT(Distance(got.map().metadata().anchor().pose(), DemoMaps()[0].truth.global_frame), 1e-3);
}

TEST_F(AnchoredQueryTest, TheSiteCommandDrawsEveryAnchoredMap) {
  const std::string base = "--server " + server_->address() + " ";
  const std::string svg = dir_.path() + "/site.svg";
  CliRun run = RunLmdctl(base + "site --collection site --out " + svg, dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(50 anchored maps, 0 of them anchored by lmdd)"), std::string::npos) << run.out;
  std::ifstream file(svg);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.rfind("<svg", 0), 0u);
  EXPECT_NE(text.find("site map of site: 50 anchored maps"), std::string::npos);

  v1::InsertMapsResponse inserted;
  ASSERT_TRUE(server_->client().InsertMaps(OneMapRequest("bare", "a", SquareRoomMap()), &inserted).ok());
  run = RunLmdctl(base + "site --collection bare --out " + svg, dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("collection 'bare' has no anchored maps"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lmd::testing
