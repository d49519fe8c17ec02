#include "datasets/synthetic_demos.h"

#include <Eigen/LU>
#include <cmath>
#include <random>

#include "core/error.h"
#include "core/portable_random.h"

namespace foresight {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string JoinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// ---- 2-D families ------------------------------------------------------------------------------

/// Base curve b(s) and b'(s) before the shift to the goal.
void BaseCurve(const std::string& shape, double s, Eigen::Vector2d* b, Eigen::Vector2d* db) {
  if (shape == "s_curve") {
    *b = {0.5 * std::cos(3 * kPi * s), 1 - s};
    *db = {-1.5 * kPi * std::sin(3 * kPi * s), -1};
  } else if (shape == "arc") {
    const double th = 1.25 * kPi * (1 - s);
    *b = {std::cos(th), std::sin(th)};
    *db = Eigen::Vector2d(-std::sin(th), std::cos(th)) * (-1.25 * kPi);
  } else {  // zigzag
    const double k = 0.3 * 2 / kPi, a = 0.95, w = 3 * kPi;
    const double sn = std::sin(w * s);
    *b = {s - 1, k * std::asin(a * sn)};
    *db = {1, k * a * w * std::cos(w * s) / std::sqrt(1 - a * a * sn * sn)};
  }
}

// ---- clamped cubic splines ---------------------------------------------------------------------

/// A C2 cubic spline through (knot_k, value_k) with zero slope at both ends, all axes at once.
class ClampedSpline {
 public:
  ClampedSpline(Eigen::VectorXd knots, Eigen::MatrixXd values)  // values [d x m+1]
      : t_(std::move(knots)), y_(std::move(values)) {
    const Eigen::Index m = t_.size() - 1;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m + 1, m + 1);
    Eigen::MatrixXd rhs(m + 1, y_.rows());
    auto slope = [&](Eigen::Index k) {  // (y_k+1 - y_k) / h_k as a row
      return ((y_.col(k + 1) - y_.col(k)) / (t_(k + 1) - t_(k))).transpose().eval();
    };
    const double h0 = t_(1) - t_(0), hm = t_(m) - t_(m - 1);
    A(0, 0) = 2 * h0, A(0, 1) = h0;
    rhs.row(0) = 6 * slope(0);
    for (Eigen::Index k = 1; k < m; ++k) {
      const double hl = t_(k) - t_(k - 1), hr = t_(k + 1) - t_(k);
      A(k, k - 1) = hl, A(k, k) = 2 * (hl + hr), A(k, k + 1) = hr;
      rhs.row(k) = 6 * (slope(k) - slope(k - 1));
    }
    A(m, m - 1) = hm, A(m, m) = 2 * hm;
    rhs.row(m) = -6 * slope(m - 1);
    M_ = A.partialPivLu().solve(rhs).transpose();  // [d x m+1] second derivatives
  }

  /// Value and first derivative at t in [t_0, t_m].
  void Evaluate(double t, Eigen::Ref<Eigen::VectorXd> value,
                Eigen::Ref<Eigen::VectorXd> slope) const {
    Eigen::Index k = 0;
    while (k + 2 < t_.size() && t > t_(k + 1)) ++k;
    const double h = t_(k + 1) - t_(k), a = t_(k + 1) - t, b = t - t_(k);
    const Eigen::VectorXd cl = y_.col(k) / h - M_.col(k) * h / 6;
    const Eigen::VectorXd cr = y_.col(k + 1) / h - M_.col(k + 1) * h / 6;
    value =
        M_.col(k) * (a * a * a / (6 * h)) + M_.col(k + 1) * (b * b * b / (6 * h)) + cl * a + cr * b;
    slope = -M_.col(k) * (a * a / (2 * h)) + M_.col(k + 1) * (b * b / (2 * h)) - cl + cr;
  }

 private:
  Eigen::VectorXd t_;
  Eigen::MatrixXd y_, M_;
};

/// A waypoint and the half-width of its per-demo uniform offset per axis (m).
struct Waypoint {
  Eigen::Vector3d p, jitter;
};

std::vector<Waypoint> TaskWaypoints(const std::string& task) {
  using V = Eigen::Vector3d;
  if (task == "push_box")
    return {{V(0.30, 0.40, 0.45), V(0.04, 0.04, 0.03)},   // start, above and behind the box
            {V(0.40, 0.30, 0.30), V(0.03, 0.03, 0.02)},   // descending toward the box
            {V(0.45, 0.21, 0.15), V(0.02, 0.02, 0.005)},  // just above the table, behind the box
            {V(0.52, 0.05, 0.12), V(0.02, 0.02, 0.005)},  // pushing
            {V(0.58, -0.10, 0.12), V(0, 0, 0)}};          // goal
  return {{V(0.30, -0.35, 0.40), V(0.04, 0.04, 0.03)},    // start
          {V(0.45, -0.15, 0.28), V(0.03, 0.03, 0.02)},    // reaching forward and down
          {V(0.54, 0.00, 0.12), V(0.015, 0.015, 0.005)},  // inside the box, low
          {V(0.54, 0.05, 0.34), V(0.015, 0.015, 0.02)},   // abruptly upward
          {V(0.52, 0.10, 0.50), V(0, 0, 0)}};             // goal
}

}  // namespace

std::vector<std::string> SyntheticShapes() { return {"arc", "s_curve", "zigzag"}; }
std::vector<std::string> TaskSpaceTasks() { return {"lift_box", "push_box"}; }

DemoSet SyntheticDemos2d(const SyntheticDemoConfig& c) {
  const std::vector<std::string> shapes = SyntheticShapes();
  FS_THROW_UNLESS(std::find(shapes.begin(), shapes.end(), c.shape) != shapes.end(),
                  "SyntheticDemos2d: unknown shape '", c.shape, "' (known: ", JoinNames(shapes),
                  ")");
  FS_THROW_UNLESS(c.demos >= 1, "SyntheticDemos2d: demos must be >= 1, got ", c.demos);
  FS_THROW_UNLESS(c.points >= 3, "SyntheticDemos2d: points must be >= 3, got ", c.points);
  FS_THROW_UNLESS(std::isfinite(c.noise) && c.noise >= 0,
                  "SyntheticDemos2d: noise must be finite and >= 0, got ", c.noise);
  Eigen::Vector2d goal_shift, unused;
  BaseCurve(c.shape, 1.0, &goal_shift, &unused);

  std::mt19937_64 rng(c.seed);
  DemoSet set;
  set.name = c.shape;
  set.dimension = 2;
  for (int i = 0; i < c.demos; ++i) {
    Eigen::Matrix<double, 2, 3> coeff;
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 2; ++r) coeff(r, k) = c.noise * StandardNormal(&rng);
    const double duration = 5.0 * (1 + c.noise * UniformSym(&rng));
    Demonstration d;
    d.position.resize(2, c.points);
    d.velocity.resize(2, c.points);
    d.time.resize(c.points);
    for (int j = 0; j < c.points; ++j) {
      const double u = static_cast<double>(j) / (c.points - 1);
      const double s = 1 - std::pow(1 - u, 3), ds_du = 3 * (1 - u) * (1 - u);
      Eigen::Vector2d b, db;
      BaseCurve(c.shape, s, &b, &db);
      // Perturbation (1 - s)^2 g(s), g = c0 + c1 sin(pi s) + c2 sin(2 pi s).
      const Eigen::Vector2d g =
          coeff.col(0) + coeff.col(1) * std::sin(kPi * s) + coeff.col(2) * std::sin(2 * kPi * s);
      const Eigen::Vector2d dg =
          coeff.col(1) * kPi * std::cos(kPi * s) + coeff.col(2) * 2 * kPi * std::cos(2 * kPi * s);
      const double w = (1 - s) * (1 - s), dw = -2 * (1 - s);
      d.position.col(j) = b - goal_shift + w * g;
      d.velocity.col(j) = (db + dw * g + w * dg) * (ds_du / duration);
      d.time(j) = u * duration;
    }
    d.position.col(c.points - 1).setZero();  // exactly the goal (b(1) - b(1) may round)
    d.velocity.col(c.points - 1).setZero();
    set.demos.push_back(std::move(d));
  }
  return set;
}

DemoSet TaskSpaceDemos(const std::string& task, int demos, std::uint64_t seed) {
  const std::vector<std::string> tasks = TaskSpaceTasks();
  FS_THROW_UNLESS(std::find(tasks.begin(), tasks.end(), task) != tasks.end(),
                  "TaskSpaceDemos: unknown task '", task, "' (known: ", JoinNames(tasks), ")");
  FS_THROW_UNLESS(demos >= 1, "TaskSpaceDemos: demos must be >= 1, got ", demos, " (task '", task,
                  "')");
  const std::vector<Waypoint> base = TaskWaypoints(task);
  const auto m = static_cast<Eigen::Index>(base.size());
  const int n = kPointsPerTaskDemo;

  std::mt19937_64 rng(seed);
  DemoSet set;
  set.name = task;
  set.dimension = 3;
  for (int i = 0; i < demos; ++i) {
    Eigen::MatrixXd values(3, m);
    for (Eigen::Index k = 0; k < m; ++k) {
      const Waypoint& w = base[static_cast<std::size_t>(k)];
      values.col(k) = w.p;
      for (int r = 0; r < 3; ++r) values(r, k) += w.jitter(r) * UniformSym(&rng);
    }
    const double duration = 5.0 + 0.5 * UniformSym(&rng);
    Eigen::VectorXd knots(m);
    knots(0) = 0;
    for (Eigen::Index k = 1; k < m; ++k)
      knots(k) = knots(k - 1) + (values.col(k) - values.col(k - 1)).norm();
    knots *= duration / knots(m - 1);
    knots(m - 1) = duration;
    const ClampedSpline spline(knots, values);

    Demonstration d;
    d.position.resize(3, n);
    d.velocity.resize(3, n);
    d.time.resize(n);
    for (int j = 0; j < n; ++j) {
      d.time(j) = duration * j / (n - 1);
      spline.Evaluate(d.time(j), d.position.col(j), d.velocity.col(j));
    }
    d.position.col(n - 1) = base.back().p;  // exactly the common goal
    d.velocity.col(n - 1).setZero();
    set.demos.push_back(std::move(d));
  }
  return set;
}

}  // namespace foresight
