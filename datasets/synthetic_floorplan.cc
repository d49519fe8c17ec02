#include "datasets/synthetic_floorplan.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

#include "core/error.h"
#include "core/geometry2d.h"
#include "core/portable_random.h"

namespace foresight {
namespace {

std::size_t UniformIndex(std::mt19937_64* rng, std::size_t n) { return (*rng)() % n; }

std::mt19937_64 Generator(std::uint64_t seed, std::uint32_t stream) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    stream};
  return std::mt19937_64(seq);
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

void AddWall(std::vector<Eigen::Vector4d>* walls, const Eigen::Vector2d& a,
             const Eigen::Vector2d& b) {
  if ((b - a).norm() > 1e-9) walls->push_back(Eigen::Vector4d(a.x(), a.y(), b.x(), b.y()));
}

int Find(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) i = (*parent)[i] = (*parent)[(*parent)[i]];
  return i;
}

/// A polyline walked at constant speed.
class Path {
 public:
  explicit Path(const Eigen::Vector2d& start) : points_{start}, cumulative_{0.0} {}
  void Append(const Eigen::Vector2d& p) {
    const double step = (p - points_.back()).norm();
    if (step < 1e-9) return;
    points_.push_back(p);
    cumulative_.push_back(cumulative_.back() + step);
  }
  double length() const { return cumulative_.back(); }
  std::size_t segments() const { return points_.size() - 1; }
  /// Position and heading (direction of the current segment) at arc length s, clamped to the end.
  void At(double s, Eigen::Vector2d* p, double* heading) const {
    std::size_t i = 0;
    while (i + 2 < points_.size() && cumulative_[i + 1] <= s) ++i;
    const Eigen::Vector2d a = points_[i], b = points_[i + 1];
    const double u =
        std::clamp((s - cumulative_[i]) / (cumulative_[i + 1] - cumulative_[i]), 0.0, 1.0);
    *p = a + u * (b - a);
    *heading = std::atan2(b.y() - a.y(), b.x() - a.x());
  }

 private:
  std::vector<Eigen::Vector2d> points_;
  std::vector<double> cumulative_;
};

}  // namespace

bool FloorPlan::Occupied(const Eigen::Vector2d& p_WP, double wall_half_thickness) const {
  for (const Eigen::Vector4d& w : walls)
    if (DistanceToSegment(p_WP, w.head<2>(), w.tail<2>()) <= wall_half_thickness) return true;
  return false;
}

double FloorPlan::Raycast(const Eigen::Vector2d& p_WO, double angle, double max_range) const {
  const Eigen::Vector2d d(std::cos(angle), std::sin(angle));
  constexpr double kEps = 1e-12;
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector4d& w : walls) {
    const Eigen::Vector2d a = w.head<2>(), e = w.tail<2>() - w.head<2>();
    const double denom = Cross(d, e);
    if (std::abs(denom) < kEps) continue;  // parallel
    const Eigen::Vector2d to_a = a - p_WO;
    const double t = Cross(to_a, e) / denom;  // along the ray
    const double u = Cross(to_a, d) / denom;  // along the wall
    if (t >= 0 && u >= -kEps && u <= 1 + kEps) best = std::min(best, t);
  }
  return best <= max_range ? best : std::numeric_limits<double>::infinity();
}

FloorPlan GenerateFloorPlan(const SyntheticFloorplanConfig& c, std::uint64_t seed) {
  FS_THROW_UNLESS(c.width > 0 && c.height > 0,
                  "synthetic floor plan: width and height must be > 0, got ", c.width, " x ",
                  c.height);
  FS_THROW_UNLESS(c.rooms_x >= 1 && c.rooms_y >= 1 && c.rooms_x * c.rooms_y >= 2,
                  "synthetic floor plan: needs at least 2 rooms, got rooms_x = ", c.rooms_x,
                  ", rooms_y = ", c.rooms_y);
  FS_THROW_UNLESS(c.door_width > 0 && c.clearance >= 0 && c.box_size > 0 && c.boxes_per_room >= 0,
                  "synthetic floor plan: door_width (", c.door_width, ") and box_size (",
                  c.box_size, ") must be > 0, clearance (", c.clearance, ") and boxes_per_room (",
                  c.boxes_per_room, ") >= 0");
  const double room_w = c.width / c.rooms_x, room_h = c.height / c.rooms_y;
  const double approach = 0.5 * c.door_width + c.clearance;
  FS_THROW_UNLESS(std::min(room_w, room_h) > 2 * approach, "synthetic floor plan: rooms of ",
                  room_w, " x ", room_h, " m are too small for doors of ", c.door_width,
                  " m with clearance ", c.clearance,
                  " m (each side must exceed door_width + 2 * clearance = ", 2 * approach, " m)");

  std::mt19937_64 rng = Generator(seed, 0);
  FloorPlan plan;
  plan.width = c.width;
  plan.height = c.height;
  const Eigen::Vector2d c00(0, 0), c10(c.width, 0), c11(c.width, c.height), c01(0, c.height);
  AddWall(&plan.walls, c00, c10);
  AddWall(&plan.walls, c10, c11);
  AddWall(&plan.walls, c11, c01);
  AddWall(&plan.walls, c01, c00);
  const int rooms = c.rooms_x * c.rooms_y;
  for (int iy = 0; iy < c.rooms_y; ++iy)
    for (int ix = 0; ix < c.rooms_x; ++ix)
      plan.room_centres.emplace_back((ix + 0.5) * room_w, (iy + 0.5) * room_h);

  // Shared walls of neighbouring rooms; doors on a random spanning tree (randomised Kruskal).
  struct Edge {
    int a, b;
    bool vertical;  // wall along y between horizontal neighbours
  };
  std::vector<Edge> edges;
  for (int iy = 0; iy < c.rooms_y; ++iy) {
    for (int ix = 0; ix < c.rooms_x; ++ix) {
      const int r = iy * c.rooms_x + ix;
      if (ix + 1 < c.rooms_x) edges.push_back({r, r + 1, true});
      if (iy + 1 < c.rooms_y) edges.push_back({r, r + c.rooms_x, false});
    }
  }
  for (std::size_t i = edges.size(); i > 1; --i)
    std::swap(edges[i - 1], edges[UniformIndex(&rng, i)]);
  std::vector<int> parent(static_cast<std::size_t>(rooms));
  std::iota(parent.begin(), parent.end(), 0);
  for (const Edge& e : edges) {
    const int ix = e.a % c.rooms_x, iy = e.a / c.rooms_x;
    // The shared wall from `lo` to `hi`, and its unit direction.
    const Eigen::Vector2d lo = e.vertical ? Eigen::Vector2d((ix + 1) * room_w, iy * room_h)
                                          : Eigen::Vector2d(ix * room_w, (iy + 1) * room_h);
    const Eigen::Vector2d along = e.vertical ? Eigen::Vector2d(0, 1) : Eigen::Vector2d(1, 0);
    const double length = e.vertical ? room_h : room_w;
    const int ra = Find(&parent, e.a), rb = Find(&parent, e.b);
    if (ra == rb) {
      AddWall(&plan.walls, lo, lo + length * along);
      continue;
    }
    parent[ra] = rb;
    const double u = approach + Uniform01(&rng) * (length - 2 * approach);
    FloorPlan::Door door;
    door.room_a = e.a;
    door.room_b = e.b;
    door.centre = lo + u * along;
    door.normal = e.vertical ? Eigen::Vector2d(1, 0) : Eigen::Vector2d(0, 1);
    door.approach = approach;
    plan.doors.push_back(door);
    AddWall(&plan.walls, lo, lo + (u - 0.5 * c.door_width) * along);
    AddWall(&plan.walls, lo + (u + 0.5 * c.door_width) * along, lo + length * along);
  }

  // Boxes: axis-aligned squares away from the room walls and from every path segment in the room.
  const double half_box = 0.5 * c.box_size, box_radius = std::sqrt(2.0) * half_box;
  for (int r = 0; r < rooms; ++r) {
    const Eigen::Vector2d centre = plan.room_centres[r];
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> paths;
    for (const FloorPlan::Door& d : plan.doors) {
      if (d.room_a != r && d.room_b != r) continue;
      const Eigen::Vector2d inward = d.room_a == r ? Eigen::Vector2d(-d.normal) : d.normal;
      const Eigen::Vector2d in_front = d.centre + d.approach * inward;
      paths.push_back({centre, in_front});
      paths.push_back({in_front, d.centre});
    }
    const double margin = half_box + c.clearance;
    const Eigen::Vector2d half_room(0.5 * room_w - margin, 0.5 * room_h - margin);
    if (half_room.minCoeff() <= 0) continue;
    std::vector<Eigen::Vector2d> placed;
    for (int attempt = 0; attempt < 100 && static_cast<int>(placed.size()) < c.boxes_per_room;
         ++attempt) {
      const Eigen::Vector2d p = centre + Eigen::Vector2d((2 * Uniform01(&rng) - 1) * half_room.x(),
                                                         (2 * Uniform01(&rng) - 1) * half_room.y());
      bool ok = true;
      for (const auto& [a, b] : paths)
        ok = ok && DistanceToSegment(p, a, b) > box_radius + c.clearance;
      for (const Eigen::Vector2d& q : placed)
        ok = ok && (p - q).cwiseAbs().maxCoeff() > c.box_size + c.clearance;
      if (!ok) continue;
      placed.push_back(p);
      const Eigen::Vector2d b00 = p + Eigen::Vector2d(-half_box, -half_box);
      const Eigen::Vector2d b10 = p + Eigen::Vector2d(half_box, -half_box);
      const Eigen::Vector2d b11 = p + Eigen::Vector2d(half_box, half_box);
      const Eigen::Vector2d b01 = p + Eigen::Vector2d(-half_box, half_box);
      AddWall(&plan.walls, b00, b10);
      AddWall(&plan.walls, b10, b11);
      AddWall(&plan.walls, b11, b01);
      AddWall(&plan.walls, b01, b00);
    }
  }
  return plan;
}

std::vector<LaserScan> SimulateRobots(const FloorPlan& plan, const SyntheticFloorplanConfig& c,
                                      std::uint64_t seed) {
  FS_THROW_UNLESS(plan.room_centres.size() >= 2 && !plan.doors.empty(),
                  "synthetic robots: the floor plan needs at least 2 rooms joined by doors, got ",
                  plan.room_centres.size(), " rooms and ", plan.doors.size(), " doors");
  FS_THROW_UNLESS(c.num_robots >= 1 && c.scans_per_robot >= 1 && c.beams >= 1,
                  "synthetic robots: num_robots (", c.num_robots, "), scans_per_robot (",
                  c.scans_per_robot, ") and beams (", c.beams, ") must be >= 1");
  FS_THROW_UNLESS(c.speed >= 0 && c.scan_period > 0 && c.max_range > 0 && c.range_noise >= 0 &&
                      c.fov > 0 && c.fov <= 2 * M_PI,
                  "synthetic robots: need speed >= 0 (", c.speed, "), scan_period > 0 (",
                  c.scan_period, "), max_range > 0 (", c.max_range, "), range_noise >= 0 (",
                  c.range_noise, "), fov in (0, 2 pi] (", c.fov, ")");
  const int rooms = static_cast<int>(plan.room_centres.size());
  std::vector<std::vector<int>> doors_of(static_cast<std::size_t>(rooms));
  for (std::size_t d = 0; d < plan.doors.size(); ++d) {
    doors_of[plan.doors[d].room_a].push_back(static_cast<int>(d));
    doors_of[plan.doors[d].room_b].push_back(static_cast<int>(d));
  }

  const double needed = (c.scans_per_robot - 1) * c.speed * c.scan_period;
  std::vector<std::vector<LaserScan>> per_robot(static_cast<std::size_t>(c.num_robots));
  for (int k = 0; k < c.num_robots; ++k) {
    std::mt19937_64 rng = Generator(seed, 1 + static_cast<std::uint32_t>(k));
    // Robots start spread over the room indices: the first in room 0, the last in the last room.
    int room = c.num_robots == 1 ? 0
                                 : static_cast<int>(std::lround(static_cast<double>(k) *
                                                                (rooms - 1) / (c.num_robots - 1)));
    std::vector<int> visits(static_cast<std::size_t>(rooms), 0);
    visits[room] = 1;
    Path path(plan.room_centres[room]);
    while (path.length() < needed || path.segments() == 0) {
      if (doors_of[room].empty()) break;  // an isolated room: stay
      // The least visited neighbour; ties broken at random.
      std::vector<int> best;
      int fewest = std::numeric_limits<int>::max();
      for (int d : doors_of[room]) {
        const FloorPlan::Door& door = plan.doors[d];
        const int next = door.room_a == room ? door.room_b : door.room_a;
        if (visits[next] < fewest) fewest = visits[next], best.clear();
        if (visits[next] == fewest) best.push_back(d);
      }
      const FloorPlan::Door& door = plan.doors[best[UniformIndex(&rng, best.size())]];
      const bool forward = door.room_a == room;
      const Eigen::Vector2d n = forward ? door.normal : Eigen::Vector2d(-door.normal);
      room = forward ? door.room_b : door.room_a;
      ++visits[room];
      path.Append(door.centre - door.approach * n);
      path.Append(door.centre);
      path.Append(door.centre + door.approach * n);
      path.Append(plan.room_centres[room]);
    }

    for (int j = 0; j < c.scans_per_robot; ++j) {
      LaserScan scan;
      scan.time = (j + static_cast<double>(k) / c.num_robots) * c.scan_period;
      scan.robot = k;
      Eigen::Vector2d p_WL(plan.room_centres[room]);
      double heading = 0;
      if (path.segments() > 0) path.At(j * c.speed * c.scan_period, &p_WL, &heading);
      scan.x = p_WL.x();
      scan.y = p_WL.y();
      scan.theta = heading;
      scan.angle_min = -0.5 * c.fov;
      scan.angle_increment = c.fov / c.beams;
      scan.ranges.resize(static_cast<std::size_t>(c.beams));
      for (int i = 0; i < c.beams; ++i) {
        const double r = plan.Raycast(p_WL, scan.BeamAngle(i), c.max_range);
        scan.ranges[i] = std::isfinite(r) ? std::max(1e-3, r + c.range_noise * StandardNormal(&rng))
                                          : c.max_range;
      }
      per_robot[k].push_back(std::move(scan));
    }
  }

  std::vector<LaserScan> scans;
  scans.reserve(static_cast<std::size_t>(c.num_robots) * c.scans_per_robot);
  for (int j = 0; j < c.scans_per_robot; ++j)
    for (int k = 0; k < c.num_robots; ++k) scans.push_back(std::move(per_robot[k][j]));
  return scans;
}

}  // namespace foresight
