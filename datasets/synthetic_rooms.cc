#include "datasets/synthetic_rooms.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <random>
#include <string>
#include <utility>

#include "core/error.h"

namespace foresight::otnet {
namespace {

constexpr double kSqrt2 = 1.41421356237309504880;
constexpr double kTwoPi = 6.28318530717958647692;

// ---------------------------------------------------------------------------------------------
// Random numbers. std::*_distribution are implementation-defined; these draws depend only on
// std::mt19937_64's (standardised) output, so a seed gives the same maps with every library.

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Uniform integer in [lo, hi] (lo <= hi), unbiased by rejection.
  int Int(int lo, int hi) {
    const std::uint64_t range = static_cast<std::uint64_t>(hi - lo) + 1;
    const std::uint64_t max = std::numeric_limits<std::uint64_t>::max();
    const std::uint64_t limit = max - max % range;
    std::uint64_t r = engine_();
    while (r >= limit) r = engine_();
    return lo + static_cast<int>(r % range);
  }
  /// Standard normal (Box-Muller, one of the pair).
  double Normal() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * Uniform());
  }
  /// Standard normal truncated to [-2, 2] (jitter never jumps far).
  double TruncatedNormal() {
    double z = Normal();
    while (std::abs(z) > 2) z = Normal();
    return z;
  }

 private:
  std::mt19937_64 engine_;
};

// ---------------------------------------------------------------------------------------------
// Geometry on the grid (cell (r, c) covers x in [c, c + 1), y in [r, r + 1)).

/// Inclusive cell rectangle.
struct Rect {
  int r0 = 0, c0 = 0, r1 = -1, c1 = -1;
  int rows() const { return r1 - r0 + 1; }
  int cols() const { return c1 - c0 + 1; }
  bool ContainsPoint(const Eigen::Vector2d& p) const {
    return p.x() >= c0 && p.x() < c1 + 1 && p.y() >= r0 && p.y() < r1 + 1;
  }
  Eigen::Vector2d Centre() const { return {0.5 * (c0 + c1 + 1), 0.5 * (r0 + r1 + 1)}; }
};

void Fill(BinaryGrid* g, const Rect& r, std::uint8_t v) {
  for (int i = r.r0; i <= r.r1; ++i)
    for (int j = r.c0; j <= r.c1; ++j) g->at(i, j) = v;
}

bool AllOccupied(const BinaryGrid& g, const Rect& r) {
  for (int i = r.r0; i <= r.r1; ++i)
    for (int j = r.c0; j <= r.c1; ++j)
      if (!g.Inside(i, j) || g.at(i, j) == 0) return false;
  return true;
}

Eigen::Vector2i CellOf(const Eigen::Vector2d& p) {
  return {static_cast<int>(std::floor(p.y())), static_cast<int>(std::floor(p.x()))};
}

/// Whether every cell whose closed square the segment a-b touches is inside and free. Stricter
/// than sampling the segment at any spacing (a segment through a cell corner needs all four).
bool SegmentFree(const BinaryGrid& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  constexpr double kEps = 1e-9;
  const double xlo = std::min(a.x(), b.x()), xhi = std::max(a.x(), b.x());
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const int c_lo = static_cast<int>(std::floor(xlo - kEps));
  const int c_hi = static_cast<int>(std::floor(xhi + kEps));
  for (int c = c_lo; c <= c_hi; ++c) {
    double y0 = std::min(a.y(), b.y()), y1 = std::max(a.y(), b.y());
    if (std::abs(dx) > 1e-12) {  // the part of the segment inside column c
      const double x0 = std::max(xlo, c - kEps), x1 = std::min(xhi, c + 1 + kEps);
      const double ya = a.y() + (x0 - a.x()) / dx * dy, yb = a.y() + (x1 - a.x()) / dx * dy;
      y0 = std::min(ya, yb);
      y1 = std::max(ya, yb);
    }
    const int r_lo = static_cast<int>(std::floor(y0 - kEps));
    const int r_hi = static_cast<int>(std::floor(y1 + kEps));
    for (int r = r_lo; r <= r_hi; ++r)
      if (!g.Inside(r, c) || g.at(r, c) != 0) return false;
  }
  return true;
}

/// Distance from p to the nearest occupied (or outside) cell square, capped at 1.
double PointClearance(const BinaryGrid& g, const Eigen::Vector2d& p) {
  const Eigen::Vector2i cell = CellOf(p);
  double best = 1.0;
  for (int r = cell.x() - 1; r <= cell.x() + 1; ++r)
    for (int c = cell.y() - 1; c <= cell.y() + 1; ++c) {
      if (g.Inside(r, c) && g.at(r, c) == 0) continue;
      const double ex = std::max({c - p.x(), 0.0, p.x() - (c + 1)});
      const double ey = std::max({r - p.y(), 0.0, p.y() - (r + 1)});
      best = std::min(best, std::hypot(ex, ey));
    }
  return best;
}

// ---------------------------------------------------------------------------------------------
// Planner: 8-connected A* with clearance-weighted move costs.

/// Per-cell cost factor 1 + w / (1 + d), d = Euclidean distance (cells, centre to centre) to the
/// nearest occupied cell, cells outside the map counting as occupied (exact EDT, OpenCV).
std::vector<double> CostFactors(const BinaryGrid& map, double clearance_weight) {
  cv::Mat free_mask(map.height + 2, map.width + 2, CV_8U, cv::Scalar(0));
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c)
      free_mask.at<std::uint8_t>(r + 1, c + 1) = map.at(r, c) == 0 ? 255 : 0;
  cv::Mat dist;
  cv::distanceTransform(free_mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  std::vector<double> factor(map.cells.size(), 1.0);
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c)
      factor[static_cast<std::size_t>(r) * map.width + c] =
          1.0 + clearance_weight / (1.0 + dist.at<float>(r + 1, c + 1));
  return factor;
}

/// The A* cell path from `from` to `to` (both free, inside), or empty when unreachable. A move
/// between neighbours u, v costs its length times the mean of their factors (symmetric, so the
/// cost of a path does not depend on its direction); the octile distance is an admissible,
/// consistent heuristic because every factor is >= 1.
std::vector<int> AStar(const BinaryGrid& map, const std::vector<double>& factor,
                       Eigen::Vector2i from, Eigen::Vector2i to) {
  const int w = map.width;
  const int n = w * map.height;
  const int start = from.x() * w + from.y(), goal = to.x() * w + to.y();
  const auto octile = [&](int cell) {
    const int dr = std::abs(cell / w - to.x()), dc = std::abs(cell % w - to.y());
    return std::max(dr, dc) + (kSqrt2 - 1.0) * std::min(dr, dc);
  };
  std::vector<double> g(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
  std::vector<int> parent(static_cast<std::size_t>(n), -1);
  std::vector<char> closed(static_cast<std::size_t>(n), 0);
  using Entry = std::pair<double, int>;  // (f, cell); ties broken by cell index: deterministic
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  g[start] = 0;
  open.emplace(octile(start), start);
  static constexpr int kDr[8] = {-1, 1, 0, 0, -1, -1, 1, 1};
  static constexpr int kDc[8] = {0, 0, -1, 1, -1, 1, -1, 1};
  while (!open.empty()) {
    const int u = open.top().second;
    open.pop();
    if (closed[u]) continue;
    closed[u] = 1;
    if (u == goal) break;
    const int ur = u / w, uc = u % w;
    for (int k = 0; k < 8; ++k) {
      const int vr = ur + kDr[k], vc = uc + kDc[k];
      if (!map.Inside(vr, vc) || map.at(vr, vc) != 0) continue;
      // A diagonal move needs both side cells free: it never cuts an occupied corner.
      if (k >= 4 && (map.at(ur + kDr[k], uc) != 0 || map.at(ur, uc + kDc[k]) != 0)) continue;
      const int v = vr * w + vc;
      if (closed[v]) continue;
      const double step = k >= 4 ? kSqrt2 : 1.0;
      const double cand = g[u] + step * 0.5 * (factor[u] + factor[v]);
      if (cand < g[v]) {
        g[v] = cand;
        parent[v] = u;
        open.emplace(cand + octile(v), v);
      }
    }
  }
  std::vector<int> path;
  if (!closed[goal]) return path;
  for (int v = goal; v != -1; v = parent[v]) path.push_back(v);
  std::reverse(path.begin(), path.end());
  return path;
}

void CheckEnd(const BinaryGrid& map, const Eigen::Vector2i& cell, const char* name) {
  FS_THROW_UNLESS(map.Inside(cell.x(), cell.y()), "PlanGridPath: ", name, " cell (row ", cell.x(),
                  ", col ", cell.y(), ") is outside the ", map.width, " x ", map.height, " map");
  FS_THROW_UNLESS(map.at(cell.x(), cell.y()) == 0, "PlanGridPath: ", name, " cell (row ", cell.x(),
                  ", col ", cell.y(), ") is occupied");
}

// ---------------------------------------------------------------------------------------------
// Layout: a corridor entering through the border wall, rooms off it, drawn in a canonical frame
// (corridor entering from the top) and then turned by a random symmetry of the square.

/// A straight corridor piece: `along` runs over rows (vertical) or columns (horizontal).
struct Segment {
  bool vertical = true;
  int a0 = 0, a1 = 0;  ///< along range
  int b0 = 0, b1 = 0;  ///< across range
  Rect ToRect() const { return vertical ? Rect{a0, b0, a1, b1} : Rect{b0, a0, b1, a1}; }
};

struct Layout {
  BinaryGrid map;
  Rect entry;                    ///< start region: the open corridor end
  Eigen::Vector2d entry_point;   ///< (x, y) where starts are centred
  std::vector<Rect> exit_rects;  ///< candidate exits: rooms and the far corridor end
};

/// One symmetry of the square: optional flips of rows and columns, then an optional transpose.
struct Symmetry {
  bool flip_r = false, flip_c = false, transpose = false;
  int size = 0;
  Eigen::Vector2i Cell(int r, int c) const {
    if (flip_r) r = size - 1 - r;
    if (flip_c) c = size - 1 - c;
    return transpose ? Eigen::Vector2i(c, r) : Eigen::Vector2i(r, c);
  }
  Eigen::Vector2d Point(Eigen::Vector2d p) const {
    if (flip_c) p.x() = size - p.x();
    if (flip_r) p.y() = size - p.y();
    return transpose ? Eigen::Vector2d(p.y(), p.x()) : p;
  }
  Rect Apply(const Rect& r) const {
    const Eigen::Vector2i a = Cell(r.r0, r.c0), b = Cell(r.r1, r.c1);
    return {std::min(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.x(), b.x()),
            std::max(a.y(), b.y())};
  }
};

/// Tries to add a room off `seg` on side `side` (+1: larger across index); false when it does
/// not fit. A room keeps a wall of >= 1 cell to every other free cell and opens onto the
/// corridor through a door of 2-3 cells.
bool TryRoom(const Segment& seg, int side, int lo, int hi, int wall, Rng& rng, BinaryGrid* g,
             std::vector<Rect>* rooms) {
  const int size = g->width;
  const int len = rng.Int(4, std::max(5, size * 45 / 100));
  // Like Occ-Traj120, rooms mostly reach from the corridor to the border wall.
  const int room_space = side > 0 ? hi - (seg.b1 + wall) : seg.b0 - wall - lo;
  if (room_space < 3) return false;
  const int depth = rng.Uniform() < 0.6 ? room_space : rng.Int(3, room_space);
  const int door = rng.Int(2, 3);
  const int a_min = std::max(lo, seg.a0 - len + door),
            a_max = std::min(hi - len + 1, seg.a1 - door + 1);
  if (a_min > a_max) return false;
  const int a0 = rng.Int(a_min, a_max), a1 = a0 + len - 1;
  int b0, b1;
  if (side > 0) {
    b0 = seg.b1 + 1 + wall;
    b1 = b0 + depth - 1;
  } else {
    b1 = seg.b0 - 1 - wall;
    b0 = b1 - depth + 1;
  }
  const Segment room_seg{seg.vertical, a0, a1, b0, b1};
  const Rect room = room_seg.ToRect();
  if (!AllOccupied(*g, Rect{room.r0 - 1, room.c0 - 1, room.r1 + 1, room.c1 + 1})) return false;
  Fill(g, room, 0);
  // The door: `door` cells along the overlap of the room and the corridor, through the wall.
  const int o0 = std::max(a0, seg.a0), o1 = std::min(a1, seg.a1);
  const int d0 = rng.Int(o0, o1 - door + 1);
  const Segment door_seg{seg.vertical, d0, d0 + door - 1, side > 0 ? seg.b1 + 1 : b1 + 1,
                         side > 0 ? b0 - 1 : seg.b0 - 1};
  Fill(g, door_seg.ToRect(), 0);
  // Large rooms sometimes hold a pillar, with a ring of >= 3 free cells around it (so the room
  // stays connected and every door stays open).
  if (room.rows() >= 9 && room.cols() >= 9 && rng.Uniform() < 0.35) {
    const int ph = rng.Int(2, std::min(4, room.rows() - 6));
    const int pw = rng.Int(2, std::min(4, room.cols() - 6));
    const int pr = rng.Int(room.r0 + 3, room.r1 - 2 - ph);
    const int pc = rng.Int(room.c0 + 3, room.c1 - 2 - pw);
    Fill(g, Rect{pr, pc, pr + ph - 1, pc + pw - 1}, 1);
  }
  rooms->push_back(room);
  return true;
}

/// One attempt at a layout in the canonical frame; false when too few rooms fitted.
bool TryCanonicalLayout(int size, Rng& rng, Layout* out) {
  BinaryGrid g(size, size);
  std::fill(g.cells.begin(), g.cells.end(), 1);
  const int border = rng.Int(1, std::max(1, size / 13));
  const int lo = border, hi = size - 1 - border;  // inner extent (rows and columns)
  const int width = rng.Int(3, 5);
  const int wall = rng.Int(1, 2);
  const int cc = rng.Int(lo, hi - width + 1);  // corridor columns [cc, cc + width - 1]
  const int r_end = rng.Int(std::min(hi, size / 2 + width), hi);

  std::vector<Segment> segments;
  // The vertical corridor runs from the top edge (through the border: the entry) to r_end.
  segments.push_back(Segment{true, 0, r_end, cc, cc + width - 1});
  Rect far_end{std::max(0, r_end - 3), cc, r_end, cc + width - 1};
  // L-shaped: an arm along the bottom toward the side with more space.
  const int space_left = cc - lo, space_right = hi - (cc + width - 1);
  if (rng.Uniform() < 0.45 && std::max(space_left, space_right) >= 6) {
    const bool left =
        space_left > space_right || (space_left == space_right && rng.Uniform() < 0.5);
    const int reach = rng.Int(6, left ? space_left : space_right);
    Segment arm{false, left ? cc - reach : cc + width, left ? cc - 1 : cc + width - 1 + reach,
                r_end - width + 1, r_end};
    segments.push_back(arm);
    far_end =
        left ? Rect{arm.b0, arm.a0, arm.b1, arm.a0 + 3} : Rect{arm.b0, arm.a1 - 3, arm.b1, arm.a1};
  }
  for (const Segment& s : segments) Fill(&g, s.ToRect(), 0);

  const int target_rooms = rng.Int(2, 5);
  std::vector<Rect> rooms;
  for (int attempt = 0; attempt < 150 && static_cast<int>(rooms.size()) < target_rooms; ++attempt) {
    Segment seg =
        segments[static_cast<std::size_t>(rng.Int(0, static_cast<int>(segments.size()) - 1))];
    if (seg.vertical) seg.a0 = std::max(seg.a0, lo);  // no rooms in the border
    TryRoom(seg, rng.Uniform() < 0.5 ? -1 : 1, lo, hi, wall, rng, &g, &rooms);
  }
  if (rooms.size() < 2) return false;

  out->map = std::move(g);
  out->entry = Rect{0, cc, std::min(r_end, 5), cc + width - 1};
  out->entry_point = Eigen::Vector2d(cc + 0.5 * width, 1.0);
  out->exit_rects = rooms;
  out->exit_rects.push_back(far_end);
  return true;
}

Layout TurnLayout(const Layout& in, const Symmetry& s) {
  Layout out;
  out.map = BinaryGrid(in.map.width, in.map.height);
  for (int r = 0; r < in.map.height; ++r)
    for (int c = 0; c < in.map.width; ++c) {
      const Eigen::Vector2i t = s.Cell(r, c);
      out.map.at(t.x(), t.y()) = in.map.at(r, c);
    }
  out.entry = s.Apply(in.entry);
  out.entry_point = s.Point(in.entry_point);
  for (const Rect& r : in.exit_rects) out.exit_rects.push_back(s.Apply(r));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Trajectories.

constexpr double kClearanceWeight = 2.0;  // planner preference for the middle of corridors
constexpr double kSmoothingMargin = 0.4;  // shortcuts keep this clearance (cells) mid-segment

/// Polyline with arc-length lookup.
class Polyline {
 public:
  explicit Polyline(std::vector<Eigen::Vector2d> pts) : pts_(std::move(pts)), cum_(pts_.size(), 0) {
    for (std::size_t i = 1; i < pts_.size(); ++i)
      cum_[i] = cum_[i - 1] + (pts_[i] - pts_[i - 1]).norm();
  }
  double Length() const { return cum_.back(); }
  Eigen::Vector2d At(double s) const {
    if (s >= Length()) return pts_.back();
    const auto it = std::upper_bound(cum_.begin(), cum_.end(), s);
    const std::size_t i = static_cast<std::size_t>(it - cum_.begin());  // s in [cum_[i-1], cum_[i])
    const double seg = cum_[i] - cum_[i - 1];
    const double t = seg > 0 ? (s - cum_[i - 1]) / seg : 0.0;
    return pts_[i - 1] + t * (pts_[i] - pts_[i - 1]);
  }

 private:
  std::vector<Eigen::Vector2d> pts_;
  std::vector<double> cum_;
};

/// A shortcut a-b is taken when it is free and, away from its ends, keeps kSmoothingMargin.
bool ShortcutClear(const BinaryGrid& map, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  if (!SegmentFree(map, a, b)) return false;
  const double len = (b - a).norm();
  for (double s = 0.5; s <= len - 0.5; s += 0.1)
    if (PointClearance(map, a + (s / len) * (b - a)) < kSmoothingMargin) return false;
  return true;
}

struct StepBounds {
  double min, max;
  bool Ok(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    const double d = (b - a).norm();
    return d >= min && d <= max;
  }
};

/// Whether the waypoints are all free, each step within bounds and each straight step free.
bool ValidTrajectory(const BinaryGrid& map, const std::vector<Eigen::Vector2d>& pts,
                     const StepBounds& bounds) {
  if (pts.size() < 2) return false;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (map.OccupiedAt(pts[i].x(), pts[i].y())) return false;
    if (i > 0 && (!bounds.Ok(pts[i - 1], pts[i]) || !SegmentFree(map, pts[i - 1], pts[i])))
      return false;
  }
  return true;
}

class TrajectoryMaker {
 public:
  TrajectoryMaker(const BinaryGrid& map, const SyntheticRoomsOptions& o)
      : map_(map),
        options_(o),
        factor_(CostFactors(map, kClearanceWeight)),
        bounds_{o.step / 3.0, 2.0 * o.step} {}

  double PathLength(const Eigen::Vector2i& from, const Eigen::Vector2i& to) const {
    const std::vector<int> cells = AStar(map_, factor_, from, to);
    if (cells.empty()) return -1;
    double len = 0;
    for (std::size_t i = 1; i < cells.size(); ++i)
      len += (cells[i] / map_.width != cells[i - 1] / map_.width &&
              cells[i] % map_.width != cells[i - 1] % map_.width)
                 ? kSqrt2
                 : 1.0;
    return len;
  }

  /// A trajectory from start to goal (both free points), or empty when a stage failed.
  std::vector<Eigen::Vector2d> Make(const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
                                    Rng& rng) const {
    const std::vector<int> cells = AStar(map_, factor_, CellOf(start), CellOf(goal));
    if (cells.empty()) return {};
    // start, the cell centres, goal: every piece is free (the ends lie in their cells, centre to
    // centre moves never cut a corner).
    std::vector<Eigen::Vector2d> raw{start};
    for (int cell : cells) raw.emplace_back(cell % map_.width + 0.5, cell / map_.width + 0.5);
    raw.push_back(goal);
    std::vector<Eigen::Vector2d> pts;
    for (const Eigen::Vector2d& p : raw)
      if (pts.empty() || (p - pts.back()).norm() > 1e-9) pts.push_back(p);
    if (pts.size() < 2) return {};

    // Shortcut smoothing: from each kept point, extend while the shortcut stays clear.
    std::vector<Eigen::Vector2d> smooth{pts.front()};
    for (std::size_t i = 0; i + 1 < pts.size();) {
      std::size_t j = i + 1;
      while (j + 1 < pts.size() && ShortcutClear(map_, pts[i], pts[j + 1])) ++j;
      smooth.push_back(pts[j]);
      i = j;
    }

    std::vector<Eigen::Vector2d> out = Resample(Polyline(std::move(smooth)));
    if (out.empty()) return out;
    Jitter(&out, rng);
    if (!ValidTrajectory(map_, out, bounds_)) return {};
    return out;
  }

 private:
  /// Points every `step` of arc length (the last two steps evened out, so no step exceeds 1.25
  /// step before jitter); a chord that would leave
  /// the free space is shortened until it does not. Empty when no admissible step exists.
  std::vector<Eigen::Vector2d> Resample(const Polyline& line) const {
    const double step = options_.step, total = line.Length();
    std::vector<Eigen::Vector2d> out{line.At(0)};
    double s = 0;
    while (total - s > 1e-9) {
      const double rem = total - s;
      double h = rem <= 1.25 * step ? rem : (rem < 2 * step ? 0.5 * rem : step);
      bool placed = false;
      for (; h >= bounds_.min * 0.999; h -= 0.1 * step) {
        // Never leave a remainder shorter than the smallest step.
        if (h < rem - 1e-9 && rem - h < bounds_.min) continue;
        const Eigen::Vector2d q = line.At(s + h);
        if (bounds_.Ok(out.back(), q) && SegmentFree(map_, out.back(), q)) {
          out.push_back(q);
          s = h >= rem - 1e-9 ? total : s + h;
          placed = true;
          break;
        }
      }
      if (!placed) return {};
    }
    return out;
  }

  /// Moves each interior waypoint by a truncated Gaussian, keeping it free, its steps in bounds
  /// and both straight steps free (the next step against the unmoved successor, which is what
  /// the following waypoint then starts from).
  void Jitter(std::vector<Eigen::Vector2d>* pts, Rng& rng) const {
    if (options_.jitter <= 0) return;
    for (std::size_t k = 1; k + 1 < pts->size(); ++k) {
      const Eigen::Vector2d& prev = (*pts)[k - 1];
      const Eigen::Vector2d& next = (*pts)[k + 1];
      for (int attempt = 0; attempt < 4; ++attempt) {
        const Eigen::Vector2d q =
            (*pts)[k] +
            options_.jitter * Eigen::Vector2d(rng.TruncatedNormal(), rng.TruncatedNormal());
        if (!map_.OccupiedAt(q.x(), q.y()) && bounds_.Ok(prev, q) && bounds_.Ok(q, next) &&
            SegmentFree(map_, prev, q) && SegmentFree(map_, q, next)) {
          (*pts)[k] = q;
          break;
        }
      }
    }
  }

  const BinaryGrid& map_;
  const SyntheticRoomsOptions& options_;
  std::vector<double> factor_;
  StepBounds bounds_;
};

/// A free point drawn around `centre` with std `spread`, inside `region`; `fallback` (free) when
/// 100 draws fail.
Eigen::Vector2d DrawPoint(const BinaryGrid& map, const Eigen::Vector2d& centre, double spread,
                          const Rect& region, const Eigen::Vector2d& fallback, Rng& rng) {
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector2d p = centre + spread * Eigen::Vector2d(rng.Normal(), rng.Normal());
    if (region.ContainsPoint(p) && !map.OccupiedAt(p.x(), p.y())) return p;
  }
  return fallback;
}

/// The free cell centre of `region` nearest to `target` (the region holds a free cell).
Eigen::Vector2d NearestFreeCentre(const BinaryGrid& map, const Rect& region,
                                  const Eigen::Vector2d& target) {
  Eigen::Vector2d best = target;
  double best_d = std::numeric_limits<double>::infinity();
  for (int r = region.r0; r <= region.r1; ++r)
    for (int c = region.c0; c <= region.c1; ++c) {
      if (map.at(r, c) != 0) continue;
      const Eigen::Vector2d p(c + 0.5, r + 0.5);
      const double d = (p - target).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = p;
      }
    }
  return best;
}

struct Exit {
  Rect region;
  Eigen::Vector2d anchor;  ///< free point goals are centred on
  double spread = 1;       ///< std of goals around the anchor (cells)
  double cumulative = 0;   ///< cumulative choice probability
};

/// Adds 1-3 pillars (2 x 2 occupied blocks with a free ring around them, away from the entry) to a
/// family's layout, keeping every exit region's centre reachable from the entry.
void AddPillars(const SyntheticRoomsOptions& o, Layout* layout, Rng& rng) {
  const int count = rng.Int(1, 3);
  BinaryGrid& g = layout->map;
  for (int p = 0, tries = 0; p < count && tries < 200; ++tries) {
    const int r = rng.Int(2, g.height - 4), c = rng.Int(2, g.width - 4);
    bool free = true;  // the block and a one-cell ring around it
    for (int rr = r - 1; rr <= r + 2 && free; ++rr)
      for (int cc = c - 1; cc <= c + 2 && free; ++cc) free = g.at(rr, cc) == 0;
    if (!free || (Eigen::Vector2d(c + 1, r + 1) - layout->entry_point).norm() < 6) continue;
    Rect block;
    block.r0 = r;
    block.c0 = c;
    block.r1 = r + 1;
    block.c1 = c + 1;
    Fill(&g, block, 1);
    const TrajectoryMaker maker(g, o);
    bool reachable = true;
    for (const Rect& region : layout->exit_rects) {
      const Eigen::Vector2d centre = NearestFreeCentre(g, region, region.Centre());
      reachable = reachable && maker.PathLength(CellOf(layout->entry_point), CellOf(centre)) >= 0;
    }
    if (reachable)
      ++p;
    else
      Fill(&g, block, 0);
  }
}

MapTrajectories GenerateMap(const SyntheticRoomsOptions& o, int k) {
  Rng rng(SplitMix64(o.seed ^ SplitMix64(static_cast<std::uint64_t>(k) + 1)));
  // With layout families, the layout, its exits and their weights come from the family's own
  // generator; the pillars and the trajectories from the map's.
  const std::uint64_t family = static_cast<std::uint64_t>(o.layouts > 0 ? k % o.layouts : k);
  Rng family_rng(o.layouts > 0 ? SplitMix64(o.seed ^ SplitMix64(family + 1) ^ 0x5bd1e995ull)
                               : SplitMix64(o.seed ^ SplitMix64(family + 1)));
  Rng& lrng = o.layouts > 0 ? family_rng : rng;
  for (int attempt = 0; attempt < 200; ++attempt) {
    Layout canonical;
    if (!TryCanonicalLayout(o.size, lrng, &canonical)) continue;
    Symmetry sym;
    sym.size = o.size;
    sym.flip_r = lrng.Uniform() < 0.5;
    sym.flip_c = lrng.Uniform() < 0.5;
    sym.transpose = lrng.Uniform() < 0.5;
    Layout layout = TurnLayout(canonical, sym);
    if (o.layouts > 0) AddPillars(o, &layout, rng);
    const TrajectoryMaker maker(layout.map, o);

    // Exits: regions whose anchor is reachable and at least four steps of path from the entry
    // (so trajectories have about five waypoints or more); 2-4 of them, map-specific weights.
    const Eigen::Vector2i entry_cell = CellOf(layout.entry_point);
    std::vector<Exit> usable;
    for (const Rect& region : layout.exit_rects) {
      Exit e;
      e.region = region;
      const Eigen::Vector2d jiggle(lrng.Uniform(-0.25, 0.25) * region.cols(),
                                   lrng.Uniform(-0.25, 0.25) * region.rows());
      e.anchor = NearestFreeCentre(layout.map, region, region.Centre() + jiggle);
      e.spread = std::clamp(0.25 * std::min(region.rows(), region.cols()), 0.5, 2.0);
      const double len = maker.PathLength(entry_cell, CellOf(e.anchor));
      if (len >= 4 * o.step) usable.push_back(e);
    }
    if (usable.size() < 2) continue;
    for (std::size_t i = usable.size() - 1; i > 0; --i)
      std::swap(usable[i], usable[static_cast<std::size_t>(lrng.Int(0, static_cast<int>(i)))]);
    usable.resize(
        static_cast<std::size_t>(std::min(lrng.Int(2, 4), static_cast<int>(usable.size()))));
    double total = 0;
    for (Exit& e : usable) total += (e.cumulative = lrng.Uniform(0.3, 1.0));
    double acc = 0;
    for (Exit& e : usable) e.cumulative = (acc += e.cumulative / total);

    MapTrajectories m;
    m.id = "synthetic_" + std::to_string(k);
    for (int t = 0; t < o.trajectories_per_map; ++t) {
      std::vector<Eigen::Vector2d> pts;
      for (int tries = 0; tries < 100 && pts.empty(); ++tries) {
        const double u = rng.Uniform();
        const Exit* exit = &usable.back();
        for (const Exit& e : usable)
          if (u < e.cumulative) {
            exit = &e;
            break;
          }
        const Eigen::Vector2d start = DrawPoint(layout.map, layout.entry_point, o.start_spread,
                                                layout.entry, layout.entry_point, rng);
        const Eigen::Vector2d goal =
            DrawPoint(layout.map, exit->anchor, exit->spread, exit->region, exit->anchor, rng);
        pts = maker.Make(start, goal, rng);
        // Occ-Traj120 has 5-58 waypoints: shorter draws are redrawn while tries remain.
        if (pts.size() < 5 && tries < 50) pts.clear();
      }
      FS_THROW_UNLESS(!pts.empty(), "GenerateRoomsAndCorridors: map ", k,
                      ": no admissible trajectory in 100 tries (step ", o.step, ", jitter ",
                      o.jitter, ")");
      Eigen::MatrixX2d traj(static_cast<Eigen::Index>(pts.size()), 2);
      for (std::size_t i = 0; i < pts.size(); ++i)
        traj.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
      m.trajectories.push_back(std::move(traj));
    }
    m.map = layout.map;
    return m;
  }
  Fail("GenerateRoomsAndCorridors: map ", k,
       ": no layout with two usable exits in 200 tries (size ", o.size, ", step ", o.step, ")");
}

}  // namespace

std::vector<MapTrajectories> GenerateRoomsAndCorridors(const SyntheticRoomsOptions& options) {
  const SyntheticRoomsOptions& o = options;
  FS_THROW_UNLESS(o.size >= 20 && o.size <= 1024, "GenerateRoomsAndCorridors: size ", o.size,
                  " is outside [20, 1024]");
  FS_THROW_UNLESS(o.maps >= 1, "GenerateRoomsAndCorridors: maps ", o.maps, " must be >= 1");
  FS_THROW_UNLESS(o.layouts >= 0, "GenerateRoomsAndCorridors: layouts ", o.layouts,
                  " must be >= 0");
  FS_THROW_UNLESS(o.trajectories_per_map >= 1, "GenerateRoomsAndCorridors: trajectories_per_map ",
                  o.trajectories_per_map, " must be >= 1");
  FS_THROW_UNLESS(std::isfinite(o.step) && o.step > 0 && o.step <= o.size / 8.0,
                  "GenerateRoomsAndCorridors: step ", o.step,
                  " is outside (0, size / 8 = ", o.size / 8.0, "]");
  FS_THROW_UNLESS(std::isfinite(o.start_spread) && o.start_spread >= 0,
                  "GenerateRoomsAndCorridors: start_spread ", o.start_spread,
                  " must be finite and >= 0");
  FS_THROW_UNLESS(std::isfinite(o.jitter) && o.jitter >= 0, "GenerateRoomsAndCorridors: jitter ",
                  o.jitter, " must be finite and >= 0");
  std::vector<MapTrajectories> out;
  out.reserve(static_cast<std::size_t>(o.maps));
  for (int k = 0; k < o.maps; ++k) out.push_back(GenerateMap(o, k));
  return out;
}

Eigen::MatrixX2d PlanGridPath(const BinaryGrid& map, Eigen::Vector2i from, Eigen::Vector2i to,
                              double clearance_weight) {
  FS_THROW_UNLESS(map.width > 0 && map.height > 0 &&
                      map.cells.size() == static_cast<std::size_t>(map.width) * map.height,
                  "PlanGridPath: map is ", map.width, " x ", map.height, " with ", map.cells.size(),
                  " cells");
  FS_THROW_UNLESS(std::isfinite(clearance_weight) && clearance_weight >= 0,
                  "PlanGridPath: clearance_weight ", clearance_weight, " must be finite and >= 0");
  CheckEnd(map, from, "from");
  CheckEnd(map, to, "to");
  const std::vector<int> cells = AStar(map, CostFactors(map, clearance_weight), from, to);
  Eigen::MatrixX2d path(static_cast<Eigen::Index>(cells.size()), 2);
  for (std::size_t i = 0; i < cells.size(); ++i)
    path.row(static_cast<Eigen::Index>(i)) << cells[i] % map.width + 0.5,
        cells[i] / map.width + 0.5;
  return path;
}

}  // namespace foresight::otnet
