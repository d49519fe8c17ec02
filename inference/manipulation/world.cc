#include "inference/manipulation/world.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "core/error.h"

namespace foresight::manipulation {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxSurfacePoints = 1e7;

// ---- kernels in the primitive's local frame -------------------------------------------------

inline double Sign(double x) { return x < 0.0 ? -1.0 : 1.0; }

/// Box centred at the origin with half sizes h: q = |p| - h, sd = |max(q, 0)| + min(max_i q_i, 0).
inline double BoxDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const double qx = std::abs(p.x()) - h.x();
  const double qy = std::abs(p.y()) - h.y();
  const double qz = std::abs(p.z()) - h.z();
  const double qmax = std::max(qx, std::max(qy, qz));
  if (qmax <= 0.0) return qmax;
  const double wx = std::max(qx, 0.0), wy = std::max(qy, 0.0), wz = std::max(qz, 0.0);
  return std::sqrt(wx * wx + wy * wy + wz * wz);
}

/// The same with the local gradient (conventions in world.h).
inline double BoxDistanceGradient(const Eigen::Vector3d& p, const Eigen::Vector3d& h,
                                  Eigen::Vector3d* g) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  int k = 0;
  if (q.y() > q(k)) k = 1;
  if (q.z() > q(k)) k = 2;
  const double qmax = q(k);
  if (qmax <= 0.0) {
    g->setZero();
    (*g)(k) = Sign(p(k));
    return qmax;
  }
  const Eigen::Vector3d w = q.cwiseMax(0.0);
  const double n = w.norm();
  *g = Eigen::Vector3d(Sign(p.x()) * w.x(), Sign(p.y()) * w.y(), Sign(p.z()) * w.z()) / n;
  return n;
}

/// Cylinder along z centred at the origin: d = (rho - r, |z| - hh),
/// sd = |max(d, 0)| + min(max(d0, d1), 0).
inline double CylinderDistance(const Eigen::Vector3d& p, double r, double hh) {
  const double d0 = std::sqrt(p.x() * p.x() + p.y() * p.y()) - r;
  const double d1 = std::abs(p.z()) - hh;
  if (d0 <= 0.0 && d1 <= 0.0) return std::max(d0, d1);
  const double w0 = std::max(d0, 0.0), w1 = std::max(d1, 0.0);
  return std::sqrt(w0 * w0 + w1 * w1);
}

inline double CylinderDistanceGradient(const Eigen::Vector3d& p, double r, double hh,
                                       Eigen::Vector3d* g) {
  const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());
  const double d0 = rho - r;
  const double d1 = std::abs(p.z()) - hh;
  // Radial unit direction; local +x on the axis, where it is undefined.
  const double ux = rho > 0.0 ? p.x() / rho : 1.0;
  const double uy = rho > 0.0 ? p.y() / rho : 0.0;
  const double sz = Sign(p.z());
  if (d0 <= 0.0 && d1 <= 0.0) {
    if (d0 >= d1) {
      *g = Eigen::Vector3d(ux, uy, 0.0);
      return d0;
    }
    *g = Eigen::Vector3d(0.0, 0.0, sz);
    return d1;
  }
  const double w0 = std::max(d0, 0.0), w1 = std::max(d1, 0.0);
  const double n = std::sqrt(w0 * w0 + w1 * w1);
  *g = Eigen::Vector3d(w0 * ux, w0 * uy, w1 * sz) / n;
  return n;
}

// ---- validation and helpers -------------------------------------------------------------------

void CheckPose(const std::string& kind, const std::string& id, const Eigen::Isometry3d& X) {
  const Eigen::Matrix3d R = X.linear();
  FS_THROW_UNLESS(X.matrix().allFinite(), kind, " '", id, "': the pose has non-finite entries");
  const double orthogonality =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  FS_THROW_UNLESS(orthogonality < 1e-6 && R.determinant() > 0.0, kind, " '", id,
                  "': the pose's rotation is not a proper rotation (|R'R - I|_max = ",
                  orthogonality, ", det = ", R.determinant(), ")");
}

void CheckPositive(const std::string& kind, const std::string& id, const char* what, double v) {
  FS_THROW_UNLESS(std::isfinite(v) && v > 0.0, kind, " '", id, "': ", what, " = ", v,
                  " must be finite and positive (m)");
}

std::string Vec(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << std::setprecision(6) << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

/// Cells no longer than `spacing` covering `length`.
int Cells(double length, double spacing) {
  return std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
}

/// Surface samples of a box in its local frame (see World::SurfacePoints).
template <typename Emit>
void BoxSurface(const Eigen::Vector3d& h, double spacing, const Emit& emit) {
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const int ni = Cells(2.0 * h(i), spacing), nj = Cells(2.0 * h(j), spacing);
    for (const double side : {-1.0, 1.0}) {
      for (int a = 0; a < ni; ++a) {
        for (int b = 0; b < nj; ++b) {
          Eigen::Vector3d p;
          p(k) = side * h(k);
          p(i) = -h(i) + (a + 0.5) * 2.0 * h(i) / ni;
          p(j) = -h(j) + (b + 0.5) * 2.0 * h(j) / nj;
          emit(p);
        }
      }
    }
  }
}

/// Surface samples of a cylinder in its local frame: wall cells (chords x height), and per cap
/// the centre plus rings at radius k r / m, k = 1..m.
template <typename Emit>
void CylinderSurface(double r, double hh, double spacing, const Emit& emit) {
  const int n_theta = std::max(3, Cells(2.0 * M_PI * r, spacing));
  const int n_z = Cells(2.0 * hh, spacing);
  for (int a = 0; a < n_theta; ++a) {
    const double theta = 2.0 * M_PI * a / n_theta;
    for (int b = 0; b < n_z; ++b)
      emit(Eigen::Vector3d(r * std::cos(theta), r * std::sin(theta),
                           -hh + (b + 0.5) * 2.0 * hh / n_z));
  }
  const int m = Cells(r, spacing);
  for (const double side : {-1.0, 1.0}) {
    emit(Eigen::Vector3d(0.0, 0.0, side * hh));
    for (int k = 1; k <= m; ++k) {
      const double rho = k * r / m;
      const int n = std::max(3, Cells(2.0 * M_PI * rho, spacing));
      for (int a = 0; a < n; ++a) {
        const double theta = 2.0 * M_PI * a / n;
        emit(Eigen::Vector3d(rho * std::cos(theta), rho * std::sin(theta), side * hh));
      }
    }
  }
}

/// Writes `row` as row `used` of `table`, growing it in steps of `lanes` rows. Padding rows have
/// a zero rotation, zero sizes and an infinite offset in columns [p, p + 3): their signed
/// distance evaluates to +infinity, so they never win the minimum.
template <typename Table, typename Row>
void AppendRow(Table* table, int used, const Row& row, int lanes, int p) {
  const Eigen::Index padded = (used + lanes) / lanes * lanes;
  if (table->rows() < padded) {
    const Eigen::Index old = table->rows();
    table->conservativeResize(padded, Eigen::NoChange);
    table->bottomRows(padded - old).setZero();
    table->bottomRows(padded - old).middleCols(p, 3).setConstant(kInf);
  }
  table->row(used) = row;
}

}  // namespace

// ---- free functions -------------------------------------------------------------------------

double SignedDistance(const Box& box, const Eigen::Vector3d& p_W, Eigen::Vector3d* grad_W) {
  const Eigen::Matrix3d R_WB = box.X_WB.linear();
  const Eigen::Vector3d p_B = R_WB.transpose() * (p_W - box.X_WB.translation());
  if (!grad_W) return BoxDistance(p_B, box.half_size);
  Eigen::Vector3d g_B;
  const double d = BoxDistanceGradient(p_B, box.half_size, &g_B);
  *grad_W = R_WB * g_B;
  return d;
}

double SignedDistance(const Cylinder& cylinder, const Eigen::Vector3d& p_W,
                      Eigen::Vector3d* grad_W) {
  const Eigen::Matrix3d R_WC = cylinder.X_WC.linear();
  const Eigen::Vector3d p_C = R_WC.transpose() * (p_W - cylinder.X_WC.translation());
  if (!grad_W) return CylinderDistance(p_C, cylinder.radius, cylinder.half_height);
  Eigen::Vector3d g_C;
  const double d = CylinderDistanceGradient(p_C, cylinder.radius, cylinder.half_height, &g_C);
  *grad_W = R_WC * g_C;
  return d;
}

Eigen::AlignedBox3d Bounds(const Box& box) {
  const Eigen::Vector3d extent = box.X_WB.linear().cwiseAbs() * box.half_size;
  const Eigen::Vector3d c = box.X_WB.translation();
  return Eigen::AlignedBox3d(c - extent, c + extent);
}

Eigen::AlignedBox3d Bounds(const Cylinder& cylinder) {
  const Eigen::Vector3d axis = cylinder.X_WC.linear().col(2);
  Eigen::Vector3d extent;
  for (int i = 0; i < 3; ++i) {
    extent(i) = cylinder.half_height * std::abs(axis(i)) +
                cylinder.radius * std::sqrt(std::max(0.0, 1.0 - axis(i) * axis(i)));
  }
  const Eigen::Vector3d c = cylinder.X_WC.translation();
  return Eigen::AlignedBox3d(c - extent, c + extent);
}

std::string Describe(const Obstacle& obstacle) {
  std::ostringstream os;
  os << std::setprecision(6);
  if (obstacle.is_box()) {
    const Box& b = obstacle.box();
    const Eigen::Quaterniond q(b.X_WB.linear());
    os << "box '" << obstacle.id << "' centre " << Vec(b.X_WB.translation()) << " half sizes "
       << Vec(b.half_size) << " quat xyzw (" << q.x() << ", " << q.y() << ", " << q.z() << ", "
       << q.w() << ")";
  } else {
    const Cylinder& c = obstacle.cylinder();
    os << "cylinder '" << obstacle.id << "' centre " << Vec(c.X_WC.translation()) << " radius "
       << c.radius << " half height " << c.half_height << " axis " << Vec(c.X_WC.linear().col(2));
  }
  return os.str();
}

// ---- World ----------------------------------------------------------------------------------

void World::CheckNewId(const std::string& id) const {
  FS_THROW_UNLESS(!id.empty(), "world: an obstacle id must not be empty");
  FS_THROW_UNLESS(FindObstacle(id) < 0, "world: duplicate obstacle id '", id, "'");
}

void World::AddBox(std::string id, const Box& box) {
  CheckNewId(id);
  CheckPose("box", id, box.X_WB);
  for (int i = 0; i < 3; ++i) CheckPositive("box", id, "half size", box.half_size(i));
  BoxSlot slot;
  slot.R_LW = box.X_WB.linear().transpose();
  slot.p_LW = -slot.R_LW * box.X_WB.translation();
  slot.half_size = box.half_size;
  Eigen::Matrix<double, 1, kBoxColumns> row;
  row << slot.R_LW.row(0), slot.R_LW.row(1), slot.R_LW.row(2), slot.p_LW.transpose(),
      slot.half_size.transpose();
  AppendRow(&box_table_, num_boxes(), row, kLanes, kBoxP);
  slot_of_.push_back(num_boxes());
  box_index_.push_back(num_obstacles());
  boxes_.push_back(slot);
  obstacles_.push_back({std::move(id), box});
  bounds_.extend(Bounds(box));
}

void World::AddCylinder(std::string id, const Cylinder& cylinder) {
  CheckNewId(id);
  CheckPose("cylinder", id, cylinder.X_WC);
  CheckPositive("cylinder", id, "radius", cylinder.radius);
  CheckPositive("cylinder", id, "half height", cylinder.half_height);
  CylinderSlot slot;
  slot.R_LW = cylinder.X_WC.linear().transpose();
  slot.p_LW = -slot.R_LW * cylinder.X_WC.translation();
  slot.radius = cylinder.radius;
  slot.half_height = cylinder.half_height;
  Eigen::Matrix<double, 1, kCylColumns> row;
  row << slot.R_LW.row(0), slot.R_LW.row(1), slot.R_LW.row(2), slot.p_LW.transpose(), slot.radius,
      slot.half_height;
  AppendRow(&cylinder_table_, num_cylinders(), row, kLanes, kCylP);
  slot_of_.push_back(num_cylinders());
  cylinder_index_.push_back(num_obstacles());
  cylinders_.push_back(slot);
  obstacles_.push_back({std::move(id), cylinder});
  bounds_.extend(Bounds(cylinder));
}

int World::FindObstacle(const std::string& id) const {
  for (int i = 0; i < num_obstacles(); ++i)
    if (obstacles_[static_cast<std::size_t>(i)].id == id) return i;
  return -1;
}

World::Lanes World::BoxLanes(int k0, double px, double py, double pz) const {
  // sd = |max(q, 0)| + min(max_i q_i, 0), q = |p_L| - h.
  auto c = [&](int j) { return box_table_.col(j).segment<kLanes>(k0).array(); };
  const Lanes qx =
      (c(kBoxR + 0) * px + c(kBoxR + 1) * py + c(kBoxR + 2) * pz + c(kBoxP + 0)).abs() -
      c(kBoxH + 0);
  const Lanes qy =
      (c(kBoxR + 3) * px + c(kBoxR + 4) * py + c(kBoxR + 5) * pz + c(kBoxP + 1)).abs() -
      c(kBoxH + 1);
  const Lanes qz =
      (c(kBoxR + 6) * px + c(kBoxR + 7) * py + c(kBoxR + 8) * pz + c(kBoxP + 2)).abs() -
      c(kBoxH + 2);
  const Lanes outside = (qx.max(0.0).square() + qy.max(0.0).square() + qz.max(0.0).square()).sqrt();
  return outside + qx.max(qy).max(qz).min(0.0);
}

World::Lanes World::CylinderLanes(int k0, double px, double py, double pz) const {
  // d = (rho - r, |z| - hh), sd = |max(d, 0)| + min(max(d0, d1), 0).
  auto c = [&](int j) { return cylinder_table_.col(j).segment<kLanes>(k0).array(); };
  const Lanes lx = c(kCylR + 0) * px + c(kCylR + 1) * py + c(kCylR + 2) * pz + c(kCylP + 0);
  const Lanes ly = c(kCylR + 3) * px + c(kCylR + 4) * py + c(kCylR + 5) * pz + c(kCylP + 1);
  const Lanes lz = c(kCylR + 6) * px + c(kCylR + 7) * py + c(kCylR + 8) * pz + c(kCylP + 2);
  const Lanes d0 = (lx.square() + ly.square()).sqrt() - c(kCylRadius);
  const Lanes d1 = lz.abs() - c(kCylHalfHeight);
  return (d0.max(0.0).square() + d1.max(0.0).square()).sqrt() + d0.max(d1).min(0.0);
}

void World::ClosestGradient(const Eigen::Vector3d& p_W, int index, Eigen::Vector3d* grad_W) const {
  if (index < 0) {
    grad_W->setZero();
    return;
  }
  const auto slot = static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(index)]);
  Eigen::Vector3d g_L;
  if (obstacles_[static_cast<std::size_t>(index)].is_box()) {
    const BoxSlot& s = boxes_[slot];
    BoxDistanceGradient(s.R_LW * p_W + s.p_LW, s.half_size, &g_L);
    *grad_W = s.R_LW.transpose() * g_L;
  } else {
    const CylinderSlot& s = cylinders_[slot];
    CylinderDistanceGradient(s.R_LW * p_W + s.p_LW, s.radius, s.half_height, &g_L);
    *grad_W = s.R_LW.transpose() * g_L;
  }
}

double World::SignedDistance(const Eigen::Vector3d& p_W, Eigen::Vector3d* grad_W,
                             int* closest) const {
  const double px = p_W.x(), py = p_W.y(), pz = p_W.z();
  if (!p_W.allFinite()) {
    if (closest) *closest = -1;
    if (grad_W) grad_W->setConstant(std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::quiet_NaN();
  }
  double best = kInf;
  int best_index = -1;
  Eigen::Index best_slot = -1;
  // Boxes, kLanes at a time.
  const int nb = num_boxes();
  for (int k0 = 0; k0 < nb; k0 += kLanes) {
    const Lanes d = BoxLanes(k0, px, py, pz);
    Eigen::Index i = 0;
    const double m = d.minCoeff(&i);  // the first lane on ties
    if (m < best) {
      best = m;
      best_slot = k0 + i;
    }
  }
  if (best_slot >= 0) best_index = box_index_[static_cast<std::size_t>(best_slot)];
  // Cylinders: ties go to the lower obstacle index.
  const int nc = num_cylinders();
  for (int k0 = 0; k0 < nc; k0 += kLanes) {
    const Lanes d = CylinderLanes(k0, px, py, pz);
    Eigen::Index i = 0;
    const double m = d.minCoeff(&i);
    if (m <= best) {
      const int index = cylinder_index_[static_cast<std::size_t>(k0 + i)];
      if (m < best || index < best_index) {
        best = m;
        best_index = index;
      }
    }
  }
  if (closest) *closest = best_index;
  if (grad_W) ClosestGradient(p_W, best_index, grad_W);
  return best;
}

void World::ObstacleDistances(const Eigen::Vector3d& p_W, double* distances) const {
  const double px = p_W.x(), py = p_W.y(), pz = p_W.z();
  const int nb = num_boxes(), nc = num_cylinders();
  for (int k0 = 0; k0 < nb; k0 += kLanes) {
    const Lanes d = BoxLanes(k0, px, py, pz);
    for (int i = 0; i < kLanes && k0 + i < nb; ++i)
      distances[box_index_[static_cast<std::size_t>(k0 + i)]] = d[i];
  }
  for (int k0 = 0; k0 < nc; k0 += kLanes) {
    const Lanes d = CylinderLanes(k0, px, py, pz);
    for (int i = 0; i < kLanes && k0 + i < nc; ++i)
      distances[cylinder_index_[static_cast<std::size_t>(k0 + i)]] = d[i];
  }
}

double World::SignedDistanceAmong(const Eigen::Vector3d& p_W, const int* obstacles, int count,
                                  Eigen::Vector3d* grad_W, int* closest) const {
  if (!p_W.allFinite()) return SignedDistance(p_W, grad_W, closest);
  const double px = p_W.x(), py = p_W.y(), pz = p_W.z();
  double best = kInf;
  int best_index = -1;
  for (int k = 0; k < count; ++k) {
    const int i = obstacles[k];
    const int slot = slot_of_[static_cast<std::size_t>(i)];
    const int k0 = slot / kLanes * kLanes;
    // The lane of the packet SignedDistance evaluates: the same number, bit for bit.
    const double d = obstacles_[static_cast<std::size_t>(i)].is_box()
                         ? BoxLanes(k0, px, py, pz)[slot - k0]
                         : CylinderLanes(k0, px, py, pz)[slot - k0];
    if (d < best) {  // ascending indices: ties keep the lower one, as SignedDistance
      best = d;
      best_index = i;
    }
  }
  if (closest) *closest = best_index;
  if (grad_W) ClosestGradient(p_W, best_index, grad_W);
  return best;
}

void World::SphereClearances(const Eigen::Ref<const Eigen::Matrix3Xd>& centres_W,
                             const Eigen::Ref<const Eigen::VectorXd>& radii,
                             Eigen::Ref<Eigen::VectorXd> clearance,
                             Eigen::Matrix3Xd* grad_W) const {
  assert(radii.size() == centres_W.cols() && clearance.size() == centres_W.cols());
  assert(!grad_W || grad_W->cols() == centres_W.cols());
  Eigen::Vector3d g;
  for (Eigen::Index s = 0; s < centres_W.cols(); ++s) {
    const Eigen::Vector3d c = centres_W.col(s);
    clearance(s) = SignedDistance(c, grad_W ? &g : nullptr) - radii(s);
    if (grad_W) grad_W->col(s) = g;
  }
}

double World::ObstacleSignedDistance(int i, const Eigen::Vector3d& p_W,
                                     Eigen::Vector3d* grad_W) const {
  const std::size_t slot = static_cast<std::size_t>(slot_of_[static_cast<std::size_t>(i)]);
  if (obstacles_[static_cast<std::size_t>(i)].is_box()) {
    const BoxSlot& s = boxes_[slot];
    const Eigen::Vector3d p_L = s.R_LW * p_W + s.p_LW;
    if (!grad_W) return BoxDistance(p_L, s.half_size);
    Eigen::Vector3d g_L;
    const double d = BoxDistanceGradient(p_L, s.half_size, &g_L);
    *grad_W = s.R_LW.transpose() * g_L;
    return d;
  }
  const CylinderSlot& s = cylinders_[slot];
  const Eigen::Vector3d p_L = s.R_LW * p_W + s.p_LW;
  if (!grad_W) return CylinderDistance(p_L, s.radius, s.half_height);
  Eigen::Vector3d g_L;
  const double d = CylinderDistanceGradient(p_L, s.radius, s.half_height, &g_L);
  *grad_W = s.R_LW.transpose() * g_L;
  return d;
}

Eigen::AlignedBox3d World::ObstacleBounds(int i) const {
  const Obstacle& o = obstacle(i);
  return o.is_box() ? Bounds(o.box()) : Bounds(o.cylinder());
}

Eigen::Matrix3Xd World::SurfacePoints(double spacing, std::vector<int>* obstacle_of_point) const {
  FS_THROW_UNLESS(std::isfinite(spacing) && spacing > 0.0,
                  "world: surface point spacing must be finite and positive, got ", spacing);
  // Count first (in double, so a tiny spacing cannot overflow), then fill.
  double total = 0;
  for (const Obstacle& o : obstacles_) {
    if (o.is_box()) {
      const Eigen::Vector3d& h = o.box().half_size;
      for (int k = 0; k < 3; ++k) {
        const double ni = std::ceil(2.0 * h((k + 1) % 3) / spacing);
        const double nj = std::ceil(2.0 * h((k + 2) % 3) / spacing);
        total += 2.0 * std::max(1.0, ni) * std::max(1.0, nj);
      }
    } else {
      const Cylinder& c = o.cylinder();
      const double wall = std::max(3.0, std::ceil(2.0 * M_PI * c.radius / spacing)) *
                          std::max(1.0, std::ceil(2.0 * c.half_height / spacing));
      const double m = std::max(1.0, std::ceil(c.radius / spacing));
      // Cap rings: sum_k max(3, ceil(2 pi k r / (m spacing))) <= 4 m + pi (m + 1) r / spacing.
      total += wall + 2.0 * (1.0 + 4.0 * m + M_PI * (m + 1.0) * c.radius / spacing);
    }
  }
  FS_THROW_UNLESS(total <= kMaxSurfacePoints, "world: surface point spacing ", spacing, " m gives ",
                  total, " points; at most ", kMaxSurfacePoints,
                  " are allowed (use a larger spacing)");
  std::vector<Eigen::Vector3d> points;
  std::vector<int> owner;
  points.reserve(static_cast<std::size_t>(total));
  for (int i = 0; i < num_obstacles(); ++i) {
    const Obstacle& o = obstacle(i);
    const Eigen::Isometry3d X = o.is_box() ? o.box().X_WB : o.cylinder().X_WC;
    auto emit = [&](const Eigen::Vector3d& p_L) {
      points.push_back(X * p_L);
      owner.push_back(i);
    };
    if (o.is_box())
      BoxSurface(o.box().half_size, spacing, emit);
    else
      CylinderSurface(o.cylinder().radius, o.cylinder().half_height, spacing, emit);
  }
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t j = 0; j < points.size(); ++j) out.col(static_cast<Eigen::Index>(j)) = points[j];
  if (obstacle_of_point) *obstacle_of_point = std::move(owner);
  return out;
}

std::string World::Summary() const {
  std::ostringstream os;
  os << num_obstacles() << " obstacles (" << num_boxes() << " boxes, " << num_cylinders()
     << " cylinders)";
  if (!bounds_.isEmpty()) os << " within " << Vec(bounds_.min()) << " .. " << Vec(bounds_.max());
  for (const Obstacle& o : obstacles_) os << "\n  " << Describe(o);
  return os.str();
}

}  // namespace foresight::manipulation
