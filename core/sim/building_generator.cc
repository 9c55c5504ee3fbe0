// GenerateWorld / GenerateBuilding (declared in world.h): Manhattan buildings
// made of blocks of rooms (or halls) between a lattice of corridors.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "core/sim/sim_random.h"
#include "core/sim/world.h"

namespace lmd {
namespace {

constexpr int kTilesPerRow = 64;

double DistToSegment(const Point2& p, const Point2& a, const Point2& b) {
  const double ex = b.x - a.x, ey = b.y - a.y;
  const double len2 = ex * ex + ey * ey;
  double t = len2 > 0 ? ((p.x - a.x) * ex + (p.y - a.y) * ey) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * ex), p.y - (a.y + t * ey));
}

// Builds one block in block-local coordinates (u along the block's long
// axis, v across it; u in [0, L], v in [0, S]), then maps to the world.
class BlockBuilder {
 public:
  BlockBuilder(const WorldOptions& opt, std::mt19937_64& rng, double bx0, double by0, double bx1,
               double by1, std::vector<Segment>* walls, std::vector<Door>* doors)
      : opt_(opt), rng_(rng), walls_(walls), doors_(doors) {
    swap_ = (by1 - by0) > (bx1 - bx0);  // long axis is y
    ox_ = bx0;
    oy_ = by0;
    L_ = swap_ ? by1 - by0 : bx1 - bx0;
    S_ = swap_ ? bx1 - bx0 : by1 - by0;
  }

  void Build() {
    if (Chance(rng_, opt_.hall_probability)) {
      BuildHall();
    } else {
      BuildRooms();
    }
    EmitBoundary();
    CorridorClutter();
  }

 private:
  struct Room {
    double u0, v0, u1, v1;
  };
  // Door on a block side: side 0: v=0, 1: v=S, 2: u=0, 3: u=L; `at` = centre
  // along the side (u for sides 0/1, v for 2/3).
  struct SideDoor {
    int side;
    double at;
  };

  Point2 W(double u, double v) const { return swap_ ? Point2{ox_ + v, oy_ + u} : Point2{ox_ + u, oy_ + v}; }
  void Wall(double u0, double v0, double u1, double v1) { walls_->push_back({W(u0, v0), W(u1, v1)}); }
  void Box(double cu, double cv, double hu, double hv, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    Point2 p[4];
    const double du[4] = {-hu, hu, hu, -hu}, dv[4] = {-hv, -hv, hv, hv};
    for (int i = 0; i < 4; ++i) p[i] = W(cu + c * du[i] - s * dv[i], cv + s * du[i] + c * dv[i]);
    for (int i = 0; i < 4; ++i) walls_->push_back({p[i], p[(i + 1) % 4]});
  }

  // Local (u, v) of a door's centre and its corridor point.
  void DoorPoints(const SideDoor& d, double* du, double* dv, double* cu, double* cv) const {
    const double half = 0.5 * opt_.corridor_width_m;
    switch (d.side) {
      case 0: *du = d.at; *dv = 0; *cu = d.at; *cv = -half; break;
      case 1: *du = d.at; *dv = S_; *cu = d.at; *cv = S_ + half; break;
      case 2: *du = 0; *dv = d.at; *cu = -half; *cv = d.at; break;
      default: *du = L_; *dv = d.at; *cu = L_ + half; *cv = d.at; break;
    }
  }

  // Adds a door on `side` of room r, returns its local path points.
  void AddDoor(const Room& r, int side, std::vector<std::pair<Point2, Point2>>* paths) {
    const double dw = opt_.door_width_m;
    const double lo = side <= 1 ? r.u0 : r.v0, hi = side <= 1 ? r.u1 : r.v1;
    if (hi - lo < dw + 1.0) return;
    SideDoor d{side, Uniform(rng_, lo + 0.5 + dw / 2, hi - 0.5 - dw / 2)};
    side_doors_.push_back(d);
    double du, dv, cu, cv;
    DoorPoints(d, &du, &dv, &cu, &cv);
    const Point2 centre{0.5 * (r.u0 + r.u1), 0.5 * (r.v0 + r.v1)};
    doors_->push_back({W(cu, cv), W(du, dv), W(centre.x, centre.y)});
    paths->push_back({Point2{du, dv}, centre});
  }

  // Boundary sides of room r (block sides it lies on).
  std::vector<int> BoundarySides(const Room& r) const {
    std::vector<int> sides;
    if (r.v0 <= 1e-9) sides.push_back(0);
    if (r.v1 >= S_ - 1e-9) sides.push_back(1);
    if (r.u0 <= 1e-9) sides.push_back(2);
    if (r.u1 >= L_ - 1e-9) sides.push_back(3);
    return sides;
  }

  bool Clear(double cu, double cv, double radius, const std::vector<std::pair<Point2, Point2>>& paths,
             double margin) const {
    for (const auto& p : paths) {
      if (DistToSegment({cu, cv}, p.first, p.second) < radius + margin) return false;
      if (std::hypot(cu - p.second.x, cv - p.second.y) < radius + 1.0) return false;  // room centre
    }
    return true;
  }

  void BuildRooms() {
    std::vector<std::pair<double, double>> rows;
    if (S_ >= 2 * opt_.min_room_m + 2.0) {
      const double mid = 0.5 * S_ + Uniform(rng_, -0.5, 0.5);
      rows = {{0, mid}, {mid, S_}};
      Wall(0, mid, L_, mid);
    } else {
      rows = {{0, S_}};
    }
    for (const auto& row : rows) {
      const int k = std::max(1, static_cast<int>(std::lround(L_ / Uniform(rng_, opt_.min_room_m, opt_.max_room_m))));
      std::vector<double> cuts(k + 1);
      for (int i = 0; i <= k; ++i) cuts[i] = L_ * i / k;
      for (int i = 1; i < k; ++i) cuts[i] += Uniform(rng_, -0.3, 0.3);
      for (int i = 0; i < k; ++i) {
        const Room r{cuts[i], row.first, cuts[i + 1], row.second};
        if (i + 1 < k) Partition(cuts[i + 1], row.first, row.second);
        FurnishRoom(r);
      }
    }
  }

  // A wall across a row at u, sometimes with a door between the rooms.
  void Partition(double u, double v0, double v1) {
    const double dw = opt_.door_width_m;
    if (v1 - v0 > dw + 1.0 && Chance(rng_, 0.3)) {
      const double at = Uniform(rng_, v0 + 0.5 + dw / 2, v1 - 0.5 - dw / 2);
      Wall(u, v0, u, at - dw / 2);
      Wall(u, at + dw / 2, u, v1);
    } else {
      Wall(u, v0, u, v1);
    }
  }

  void FurnishRoom(const Room& r) {
    std::vector<int> sides = BoundarySides(r);
    std::vector<int> long_sides;
    for (int s : sides)
      if (s <= 1) long_sides.push_back(s);
    const std::vector<int>& pick = long_sides.empty() ? sides : long_sides;
    if (pick.empty()) return;
    std::vector<std::pair<Point2, Point2>> paths;
    const int first = pick[rng_() % pick.size()];
    AddDoor(r, first, &paths);
    if (sides.size() > 1 && Chance(rng_, 0.25)) {
      int second = sides[rng_() % sides.size()];
      if (second != first) AddDoor(r, second, &paths);
    }
    // An oblique wall across one corner, away from the doors.
    if (Chance(rng_, opt_.oblique_fraction)) {
      const double a = Uniform(rng_, 1.0, std::min(2.0, 0.45 * std::min(r.u1 - r.u0, r.v1 - r.v0)));
      const int corner = UniformInt(rng_, 0, 3);
      const double cu = (corner & 1) ? r.u1 : r.u0, cv = (corner & 2) ? r.v1 : r.v0;
      bool ok = a >= 1.0;
      for (const auto& p : paths) {
        if (std::abs(p.first.x - cu) + std::abs(p.first.y - cv) < a + 0.3 + opt_.door_width_m / 2) ok = false;
      }
      if (ok) {
        const double su = (corner & 1) ? -a : a, sv = (corner & 2) ? -a : a;
        Wall(cu + su, cv, cu, cv + sv);
        chamfer_ = {cu, cv, a};
        has_chamfer_ = true;
      }
    }
    // Clutter boxes along the room's walls.
    const int n = (Chance(rng_, opt_.clutter_per_room / 3) ? 1 : 0) + (Chance(rng_, opt_.clutter_per_room / 3) ? 1 : 0) +
                  (Chance(rng_, opt_.clutter_per_room / 3) ? 1 : 0);
    for (int i = 0; i < n; ++i) {
      for (int attempt = 0; attempt < 10; ++attempt) {
        const double hu = Uniform(rng_, 0.15, 0.5), hv = Uniform(rng_, 0.15, 0.5);
        const bool rotated = Chance(rng_, 0.2);
        const double radius = rotated ? std::hypot(hu, hv) : std::max(hu, hv);
        const double gap = Uniform(rng_, 0.05, 0.3);
        double cu = 0, cv = 0;
        switch (UniformInt(rng_, 0, 3)) {
          case 0: cu = Uniform(rng_, r.u0 + radius, r.u1 - radius); cv = r.v0 + gap + radius; break;
          case 1: cu = Uniform(rng_, r.u0 + radius, r.u1 - radius); cv = r.v1 - gap - radius; break;
          case 2: cu = r.u0 + gap + radius; cv = Uniform(rng_, r.v0 + radius, r.v1 - radius); break;
          default: cu = r.u1 - gap - radius; cv = Uniform(rng_, r.v0 + radius, r.v1 - radius); break;
        }
        if (cu - radius < r.u0 + 0.02 || cu + radius > r.u1 - 0.02 || cv - radius < r.v0 + 0.02 ||
            cv + radius > r.v1 - 0.02)
          continue;
        if (!Clear(cu, cv, radius, paths, 0.6)) continue;
        if (has_chamfer_ && std::abs(cu - chamfer_[0]) + std::abs(cv - chamfer_[1]) < chamfer_[2] + 1.5 * radius) continue;
        if (rotated) {
          Box(cu, cv, hu, hv, Uniform(rng_, 0.2, 1.37));
        } else {
          Box(cu, cv, hu, hv, 0.0);
        }
        break;
      }
    }
    has_chamfer_ = false;
  }

  void BuildHall() {
    const Room r{0, 0, L_, S_};
    std::vector<int> sides = {0, 1, 2, 3};
    std::vector<std::pair<Point2, Point2>> paths;
    const int first = UniformInt(rng_, 0, 1);
    AddDoor(r, first, &paths);
    AddDoor(r, 1 - first, &paths);
    if (Chance(rng_, 0.5)) AddDoor(r, UniformInt(rng_, 2, 3), &paths);
    // Pillars on a regular grid, clear of the door paths and walls.
    const double pitch = Uniform(rng_, 3.0, 4.5);
    const double half = Uniform(rng_, 0.15, 0.3);
    for (double u = pitch; u < L_ - 1.0; u += pitch) {
      for (double v = pitch; v < S_ - 1.0; v += pitch) {
        if (!Clear(u, v, half * 1.5, paths, 0.8)) continue;
        Box(u, v, half, half, 0.0);
      }
    }
  }

  // Block sides minus door openings.
  void EmitBoundary() {
    const double dw = opt_.door_width_m;
    for (int side = 0; side < 4; ++side) {
      const double len = side <= 1 ? L_ : S_;
      std::vector<double> gaps;
      for (const SideDoor& d : side_doors_)
        if (d.side == side) gaps.push_back(d.at);
      std::sort(gaps.begin(), gaps.end());
      double from = 0.0;
      auto emit = [&](double a, double b) {
        if (b - a < 1e-6) return;
        switch (side) {
          case 0: Wall(a, 0, b, 0); break;
          case 1: Wall(a, S_, b, S_); break;
          case 2: Wall(0, a, 0, b); break;
          default: Wall(L_, a, L_, b); break;
        }
      };
      for (double g : gaps) {
        emit(from, g - dw / 2);
        from = g + dw / 2;
      }
      emit(from, len);
    }
  }

  // Sometimes a small box against the block's outside wall, in the corridor.
  void CorridorClutter() {
    for (int side = 0; side < 4; ++side) {
      if (!Chance(rng_, opt_.corridor_clutter_probability)) continue;
      const double len = side <= 1 ? L_ : S_;
      if (len < 3.0) continue;
      const double at = Uniform(rng_, 1.0, len - 1.0);
      bool ok = true;
      for (const SideDoor& d : side_doors_)
        if (d.side == side && std::abs(d.at - at) < opt_.door_width_m / 2 + 1.0) ok = false;
      if (!ok) continue;
      const double h = Uniform(rng_, 0.12, 0.2);  // half size: at most 0.4 m deep
      switch (side) {
        case 0: Box(at, -h - 0.01, h, h, 0); break;
        case 1: Box(at, S_ + h + 0.01, h, h, 0); break;
        case 2: Box(-h - 0.01, at, h, h, 0); break;
        default: Box(L_ + h + 0.01, at, h, h, 0); break;
      }
    }
  }

  const WorldOptions& opt_;
  std::mt19937_64& rng_;
  std::vector<Segment>* walls_;
  std::vector<Door>* doors_;
  bool swap_ = false;
  double ox_ = 0, oy_ = 0, L_ = 0, S_ = 0;
  std::vector<SideDoor> side_doors_;
  bool has_chamfer_ = false;
  std::array<double, 3> chamfer_{};
};

void AppendBuilding(const WorldOptions& opt, uint64_t index, std::vector<Segment>* walls,
                    std::vector<BuildingLayout>* layouts) {
  std::mt19937_64 rng(MixSeed(opt.seed, index));
  BuildingLayout b;
  b.corridor_width = opt.corridor_width_m;
  const double ox = static_cast<double>(index % kTilesPerRow) * opt.tile_m;
  const double oy = static_cast<double>(index / kTilesPerRow) * opt.tile_m;
  const int lo = std::max(2, opt.min_corridors), hi = std::max(lo, opt.max_corridors);
  const int ncx = UniformInt(rng, lo, hi), ncy = UniformInt(rng, lo, hi);
  const double half = 0.5 * opt.corridor_width_m;
  b.corridor_x.push_back(ox + half);
  for (int i = 1; i < ncx; ++i) b.corridor_x.push_back(b.corridor_x.back() + Uniform(rng, opt.min_block_m, opt.max_block_m));
  b.corridor_y.push_back(oy + half);
  for (int i = 1; i < ncy; ++i) b.corridor_y.push_back(b.corridor_y.back() + Uniform(rng, opt.min_block_m, opt.max_block_m));
  b.min_corner = {ox, oy};
  b.max_corner = {b.corridor_x.back() + half, b.corridor_y.back() + half};
  const Point2 c0 = b.min_corner, c1 = b.max_corner;
  walls->push_back({{c0.x, c0.y}, {c1.x, c0.y}});
  walls->push_back({{c1.x, c0.y}, {c1.x, c1.y}});
  walls->push_back({{c1.x, c1.y}, {c0.x, c1.y}});
  walls->push_back({{c0.x, c1.y}, {c0.x, c0.y}});
  for (int i = 0; i + 1 < ncx; ++i) {
    for (int j = 0; j + 1 < ncy; ++j) {
      BlockBuilder block(opt, rng, b.corridor_x[i] + half, b.corridor_y[j] + half, b.corridor_x[i + 1] - half,
                         b.corridor_y[j + 1] - half, walls, &b.doors);
      block.Build();
    }
  }
  layouts->push_back(std::move(b));
}

}  // namespace

World GenerateWorld(const WorldOptions& options) {
  std::vector<Segment> walls;
  std::vector<BuildingLayout> layouts;
  for (int k = 0; k < options.buildings; ++k) AppendBuilding(options, static_cast<uint64_t>(k), &walls, &layouts);
  return World(std::move(walls), std::move(layouts));
}

World GenerateBuilding(const WorldOptions& options, uint64_t index) {
  std::vector<Segment> walls;
  std::vector<BuildingLayout> layouts;
  AppendBuilding(options, index, &walls, &layouts);
  return World(std::move(walls), std::move(layouts));
}

}  // namespace lmd
