#include "inference/navigation/goal_distance.h"

#include <cmath>
#include <limits>
#include <queue>

namespace foresight::nav {

GoalDistanceField::GoalDistanceField(const StaticCollisionField& field, const Eigen::Vector2d& goal,
                                     double epsilon, double margin, double margin_weight)
    : goal_(goal),
      origin_(field.origin()),
      resolution_(field.resolution()),
      margin_weight_(margin_weight) {
  const Eigen::MatrixXf& occ = field.raster();
  const int rows = static_cast<int>(occ.rows()), cols = static_cast<int>(occ.cols());
  constexpr float kInf = std::numeric_limits<float>::infinity();
  distance_ = Eigen::MatrixXf::Constant(rows, cols, kInf);
  if (rows == 0 || cols == 0) return;
  // Start cell: the goal's cell, or the nearest free cell to it.
  const int gc = std::clamp(static_cast<int>(std::lround((goal.x() - origin_.x()) / resolution_)),
                            0, cols - 1);
  const int gr = std::clamp(static_cast<int>(std::lround((goal.y() - origin_.y()) / resolution_)),
                            0, rows - 1);
  int sr = -1, sc = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int radius = 0; radius < std::max(rows, cols) && sr < 0; ++radius)
    for (int r = std::max(0, gr - radius); r <= std::min(rows - 1, gr + radius); ++r)
      for (int c = std::max(0, gc - radius); c <= std::min(cols - 1, gc + radius); ++c) {
        if (occ(r, c) > epsilon) continue;
        const double d = std::hypot(r - gr, c - gc);
        if (d < best) best = d, sr = r, sc = c;
      }
  if (sr < 0) return;
  using Item = std::pair<float, int>;
  // Distance of every free cell to the nearest blocked one (8-connected chamfer, in metres).
  Eigen::MatrixXf clearance = Eigen::MatrixXf::Constant(rows, cols, kInf);
  {
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        if (occ(r, c) > epsilon) {
          clearance(r, c) = 0;
          q.push({0.0f, r * cols + c});
        }
    const float hs = static_cast<float>(resolution_),
                ds = static_cast<float>(resolution_ * M_SQRT2);
    while (!q.empty()) {
      const auto [d, k] = q.top();
      q.pop();
      const int r = k / cols, c = k % cols;
      if (d > clearance(r, c) || d > margin) continue;
      for (int dr = -1; dr <= 1; ++dr)
        for (int dc = -1; dc <= 1; ++dc) {
          const int nr = r + dr, nc = c + dc;
          if ((dr == 0 && dc == 0) || nr < 0 || nc < 0 || nr >= rows || nc >= cols) continue;
          const float nd = d + (dr != 0 && dc != 0 ? ds : hs);
          if (nd < clearance(nr, nc)) {
            clearance(nr, nc) = nd;
            q.push({nd, nr * cols + nc});
          }
        }
    }
  }
  auto weight = [&](int r, int c) {
    const double d = clearance(r, c);
    return static_cast<float>(
        1.0 + (margin > 0 && d < margin ? margin_weight * (1.0 - d / margin) : 0.0));
  };
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  const Eigen::Vector2d start_cell = origin_ + resolution_ * Eigen::Vector2d(sc, sr);
  distance_(sr, sc) = static_cast<float>((start_cell - goal).norm());
  queue.push({distance_(sr, sc), sr * cols + sc});
  const float h = static_cast<float>(resolution_), diag = static_cast<float>(resolution_ * M_SQRT2);
  while (!queue.empty()) {
    const auto [d, k] = queue.top();
    queue.pop();
    const int r = k / cols, c = k % cols;
    if (d > distance_(r, c)) continue;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        if (dr == 0 && dc == 0) continue;
        const int nr = r + dr, nc = c + dc;
        if (nr < 0 || nc < 0 || nr >= rows || nc >= cols || occ(nr, nc) > epsilon) continue;
        const float nd =
            d + (dr != 0 && dc != 0 ? diag : h) * 0.5f * (weight(r, c) + weight(nr, nc));
        if (nd < distance_(nr, nc)) {
          distance_(nr, nc) = nd;
          queue.push({nd, nr * cols + nc});
        }
      }
  }
}

double GoalDistanceField::Distance(const Eigen::Vector2d& x) const {
  const double euclid = (x - goal_).norm();
  if (empty()) return euclid;
  const double u = (x.x() - origin_.x()) / resolution_, v = (x.y() - origin_.y()) / resolution_;
  if (!(u >= 0 && v >= 0 && u < distance_.cols() - 1 && v < distance_.rows() - 1))
    return euclid + unreachable_penalty;
  const int c = static_cast<int>(u), r = static_cast<int>(v);
  const double fu = u - c, fv = v - r;
  const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
  const float d[4] = {distance_(r, c), distance_(r, c + 1), distance_(r + 1, c),
                      distance_(r + 1, c + 1)};
  double sum = 0, wsum = 0;
  for (int i = 0; i < 4; ++i)
    if (std::isfinite(d[i])) sum += w[i] * d[i], wsum += w[i];
  if (wsum < 1e-9) return euclid + unreachable_penalty;
  return sum / wsum;
}

}  // namespace foresight::nav
