#include "models/directional/directional_grid_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"
#include "core/log.h"

namespace foresight::directional {
namespace {

constexpr double kLogTwoPi = 1.8378770664093454836;

double Uniform01(std::mt19937_64* rng) { return static_cast<double>((*rng)() >> 11) * 0x1.0p-53; }

/// A mixture under construction for one cell.
struct Mixture {
  std::vector<double> alpha, mu, kappa;
  std::size_t size() const { return alpha.size(); }
};

/// log-likelihood of `theta` under `m`; fills resp [n x R] with the responsibilities when given.
double MixtureLogLikelihood(const std::vector<double>& theta, const Mixture& m,
                            Eigen::MatrixXd* resp) {
  const std::size_t n = theta.size(), r = m.size();
  std::vector<double> log_c(r);
  for (std::size_t k = 0; k < r; ++k)
    log_c[k] = std::log(m.alpha[k]) - kLogTwoPi - LogBesselI0Scaled(m.kappa[k]);
  if (resp) resp->resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(r));
  double ll = 0;
  std::vector<double> lp(r);
  for (std::size_t i = 0; i < n; ++i) {
    double top = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < r; ++k) {
      const double s = std::sin(0.5 * (theta[i] - m.mu[k]));
      lp[k] = log_c[k] - 2.0 * m.kappa[k] * s * s;  // log alpha_k + log VM(theta_i; mu_k, kappa_k)
      top = std::max(top, lp[k]);
    }
    double sum = 0;
    for (std::size_t k = 0; k < r; ++k) sum += std::exp(lp[k] - top);
    ll += top + std::log(sum);
    if (resp)
      for (std::size_t k = 0; k < r; ++k)
        (*resp)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
            std::exp(lp[k] - top) / sum;
  }
  return ll;
}

/// Spherical k-means of the headings into at most `r` clusters (k-means++ seeding); empty
/// clusters are dropped. Returns each cluster's share and ML von Mises as the initial mixture.
Mixture KMeansOnCircle(const std::vector<double>& theta, int r, double max_kappa,
                       std::mt19937_64* rng) {
  const std::size_t n = theta.size();
  std::vector<double> centre;
  centre.push_back(theta[static_cast<std::size_t>((*rng)() % n)]);
  std::vector<double> d2(n);
  while (static_cast<int>(centre.size()) < r) {
    double total = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double best = std::numeric_limits<double>::infinity();
      for (double c : centre) best = std::min(best, 1.0 - std::cos(theta[i] - c));
      d2[i] = std::max(0.0, best);
      total += d2[i];
    }
    if (total <= 1e-300) break;  // fewer distinct headings than clusters
    double u = Uniform01(rng) * total;
    std::size_t pick = n - 1;
    for (std::size_t i = 0; i < n; ++i) {
      u -= d2[i];
      if (u < 0) {
        pick = i;
        break;
      }
    }
    centre.push_back(theta[pick]);
  }
  std::vector<int> label(n, -1);
  std::vector<double> c_sum, s_sum, count;
  for (int it = 0; it < 50; ++it) {
    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      int best = 0;
      double best_cos = -2;
      for (std::size_t k = 0; k < centre.size(); ++k) {
        const double c = std::cos(theta[i] - centre[k]);
        if (c > best_cos) best_cos = c, best = static_cast<int>(k);
      }
      changed |= label[i] != best;
      label[i] = best;
    }
    c_sum.assign(centre.size(), 0);
    s_sum.assign(centre.size(), 0);
    count.assign(centre.size(), 0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(label[i]);
      c_sum[k] += std::cos(theta[i]);
      s_sum[k] += std::sin(theta[i]);
      count[k] += 1;
    }
    for (std::size_t k = 0; k < centre.size(); ++k)
      if (count[k] > 0 && std::hypot(c_sum[k], s_sum[k]) > 0)
        centre[k] = std::atan2(s_sum[k], c_sum[k]);
    if (!changed) break;
  }
  Mixture m;
  for (std::size_t k = 0; k < centre.size(); ++k) {
    if (count[k] == 0) continue;
    m.alpha.push_back(count[k] / static_cast<double>(n));
    m.mu.push_back(WrapAngle(centre[k]));
    m.kappa.push_back(
        std::min(max_kappa, InverseA1(std::min(1.0, std::hypot(c_sum[k], s_sum[k]) / count[k]))));
  }
  return m;
}

/// DBSCAN (Ester et al. 1996, as scikit-learn: a point is core when at least `min_samples` points,
/// itself included, are within chord distance `eps` on the unit circle; clusters are the
/// eps-connected components of core points plus the border points they reach first). Returns
/// the initial mixture of the `max_clusters` largest clusters (alphas renormalised); empty when
/// every point is noise.
Mixture DbscanOnCircle(const std::vector<double>& theta, double eps, int min_samples,
                       int max_clusters, double max_kappa) {
  const std::size_t n = theta.size();
  std::vector<double> c(n), s(n);
  for (std::size_t i = 0; i < n; ++i) c[i] = std::cos(theta[i]), s[i] = std::sin(theta[i]);
  // |u_i - u_j|^2 = 2 - 2 cos(theta_i - theta_j) <= eps^2.
  const double min_cos = 1.0 - 0.5 * eps * eps;
  auto near = [&](std::size_t i, std::size_t j) { return c[i] * c[j] + s[i] * s[j] >= min_cos; };
  std::vector<char> core(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    int count = 0;
    for (std::size_t j = 0; j < n && count < min_samples; ++j) count += near(i, j);
    core[i] = count >= min_samples;
  }
  std::vector<int> label(n, -1);
  std::vector<std::size_t> stack;
  int clusters = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!core[i] || label[i] >= 0) continue;
    label[i] = clusters;
    stack.assign(1, i);
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      for (std::size_t j = 0; j < n; ++j) {
        if (label[j] >= 0 || !near(p, j)) continue;
        label[j] = clusters;
        if (core[j]) stack.push_back(j);
      }
    }
    ++clusters;
  }
  struct Cluster {
    double c = 0, s = 0, count = 0;
  };
  std::vector<Cluster> sums(static_cast<std::size_t>(clusters));
  for (std::size_t i = 0; i < n; ++i) {
    if (label[i] < 0) continue;
    Cluster& k = sums[static_cast<std::size_t>(label[i])];
    k.c += c[i], k.s += s[i], k.count += 1;
  }
  std::stable_sort(sums.begin(), sums.end(),
                   [](const Cluster& a, const Cluster& b) { return a.count > b.count; });
  if (static_cast<int>(sums.size()) > max_clusters)
    sums.resize(static_cast<std::size_t>(max_clusters));
  double total = 0;
  for (const Cluster& k : sums) total += k.count;
  Mixture m;
  for (const Cluster& k : sums) {
    m.alpha.push_back(k.count / total);
    m.mu.push_back(WrapAngle(std::atan2(k.s, k.c)));
    m.kappa.push_back(
        std::min(max_kappa, InverseA1(std::min(1.0, std::hypot(k.c, k.s) / k.count))));
  }
  return m;
}

/// EM for a von Mises mixture from `m`; returns the final log-likelihood.
double RefineByEm(const std::vector<double>& theta, int iterations, double max_kappa, Mixture* m) {
  const auto n = static_cast<Eigen::Index>(theta.size());
  const Eigen::Map<const Eigen::VectorXd> th(theta.data(), n);
  Eigen::MatrixXd resp;
  double ll = MixtureLogLikelihood(theta, *m, &resp);
  for (int it = 0; it < iterations; ++it) {
    Mixture next;
    for (Eigen::Index k = 0; k < resp.cols(); ++k) {
      const double share = resp.col(k).sum();
      if (share < 1e-9 * static_cast<double>(n)) continue;  // vanished component
      const VonMisesFit fit = FitVonMises(th, resp.col(k));
      next.alpha.push_back(share / static_cast<double>(n));
      next.mu.push_back(fit.mu);
      next.kappa.push_back(std::min(max_kappa, fit.kappa));
    }
    const double next_ll = MixtureLogLikelihood(theta, next, &resp);
    *m = std::move(next);
    const bool done = next_ll - ll < 1e-9 * static_cast<double>(n);
    ll = next_ll;
    if (done) break;
  }
  return ll;
}

/// Fits one cell's row of `cells` from its headings (see the header for the rules).
void FitCell(const std::vector<double>& theta, const GridConfig& c, std::uint64_t cell_seed,
             VonMisesMixtureBatch* cells, Eigen::Index row) {
  cells->alpha.row(row).setZero();
  cells->mu.row(row).setZero();
  cells->kappa.row(row).setZero();
  if (theta.empty()) {
    cells->alpha(row, 0) = 1.0;  // uniform on the circle
    return;
  }
  const auto n = static_cast<Eigen::Index>(theta.size());
  if (c.kind == GridKind::kUnimodal) {
    const VonMisesFit fit =
        FitVonMises(Eigen::Map<const Eigen::VectorXd>(theta.data(), n), Eigen::VectorXd::Ones(n));
    cells->alpha(row, 0) = 1.0;
    cells->mu(row, 0) = fit.mu;
    cells->kappa(row, 0) = std::min(c.max_kappa, fit.kappa);
    return;
  }
  if (c.mixture_init == GridMixtureInit::kDbscan) {
    Mixture m =
        DbscanOnCircle(theta, c.dbscan_eps, c.dbscan_min_samples, c.components, c.max_kappa);
    if (m.size() == 0) {  // all noise: one component from every heading
      const VonMisesFit fit =
          FitVonMises(Eigen::Map<const Eigen::VectorXd>(theta.data(), n), Eigen::VectorXd::Ones(n));
      m.alpha = {1.0};
      m.mu = {fit.mu};
      m.kappa = {std::min(c.max_kappa, fit.kappa)};
    }
    RefineByEm(theta, c.em_iterations, c.max_kappa, &m);
    for (std::size_t k = 0; k < m.size(); ++k) {
      const auto col = static_cast<Eigen::Index>(k);
      cells->alpha(row, col) = m.alpha[k];
      cells->mu(row, col) = m.mu[k];
      cells->kappa(row, col) = m.kappa[k];
    }
    return;
  }
  const int r_max = static_cast<int>(std::min<Eigen::Index>(c.components, n));
  const int r_min = c.mixture_init == GridMixtureInit::kKMeansBic ? 1 : r_max;
  Mixture best;
  double best_bic = std::numeric_limits<double>::infinity();
  for (int r = r_min; r <= r_max; ++r) {
    std::mt19937_64 rng(cell_seed ^ (0x9E3779B97F4A7C15ull * static_cast<std::uint64_t>(r)));
    Mixture m = KMeansOnCircle(theta, r, c.max_kappa, &rng);
    const double ll = RefineByEm(theta, c.em_iterations, c.max_kappa, &m);
    const double bic =
        -2.0 * ll + (3.0 * static_cast<double>(m.size()) - 1.0) * std::log(static_cast<double>(n));
    if (bic < best_bic) best_bic = bic, best = std::move(m);
  }
  for (std::size_t k = 0; k < best.size(); ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    cells->alpha(row, col) = best.alpha[k];
    cells->mu(row, col) = best.mu[k];
    cells->kappa(row, col) = best.kappa[k];
  }
}

}  // namespace

GridMap GridMap::Fit(const DirectionalSamples& train, const GridConfig& config) {
  const auto& c = config;
  FS_THROW_UNLESS(
      c.cells_x >= 1 && c.cells_y >= 1 && static_cast<double>(c.cells_x) * c.cells_y <= 16777216.0,
      "directional grid map: cells_x ", c.cells_x, " and cells_y ", c.cells_y,
      " must be >= 1 (at most 2^24 cells)");
  FS_THROW_UNLESS(c.extent.allFinite() && c.extent[1] > c.extent[0] && c.extent[3] > c.extent[2],
                  "directional grid map: extent (x_min, x_max, y_min, y_max) = (", c.extent[0],
                  ", ", c.extent[1], ", ", c.extent[2], ", ", c.extent[3],
                  ") is empty or not finite");
  FS_THROW_UNLESS(c.components >= 1 && c.components <= 64, "directional grid map: components ",
                  c.components, " must be in [1, 64]");
  FS_THROW_UNLESS(c.length_scale > 0 && std::isfinite(c.length_scale),
                  "directional grid map: length_scale ", c.length_scale, " must be positive");
  FS_THROW_UNLESS(c.max_kappa > 0 && c.em_iterations >= 0, "directional grid map: max_kappa ",
                  c.max_kappa, " must be positive and em_iterations ", c.em_iterations,
                  " non-negative");
  FS_THROW_UNLESS(c.dbscan_eps > 0 && c.dbscan_min_samples >= 1,
                  "directional grid map: dbscan_eps ", c.dbscan_eps,
                  " must be positive and dbscan_min_samples ", c.dbscan_min_samples, " >= 1");
  train.Validate("directional grid map training data");

  GridMap map;
  map.config_ = c;
  map.cell_w_ = (c.extent[1] - c.extent[0]) / c.cells_x;
  map.cell_h_ = (c.extent[3] - c.extent[2]) / c.cells_y;
  map.radius_ = std::max(map.cell_w_, map.cell_h_);
  if (c.dense) {
    // Any cell whose centre is within radius_ of a point in cell (ix, iy) lies within these
    // half-widths: its centre is at least (|j - ix| - 1/2) w away along x.
    map.window_x_ = static_cast<int>(std::ceil(map.radius_ / map.cell_w_ - 1e-12));
    map.window_y_ = static_cast<int>(std::ceil(map.radius_ / map.cell_h_ - 1e-12));
    map.window_x_ = std::min(map.window_x_, c.cells_x - 1);
    map.window_y_ = std::min(map.window_y_, c.cells_y - 1);
  }
  map.window_cells_ = (2 * map.window_x_ + 1) * (2 * map.window_y_ + 1);
  const int r = c.kind == GridKind::kUnimodal ? 1 : c.components;
  const int cells = map.num_cells();
  map.cells_.Resize(cells, r);
  map.counts_.assign(static_cast<std::size_t>(cells), 0);

  // Headings per cell: the cell holding the point, or (dense) every disc that contains it.
  std::vector<std::vector<double>> theta(static_cast<std::size_t>(cells));
  const double r2 = map.radius_ * map.radius_;
  for (Eigen::Index i = 0; i < train.size(); ++i) {
    // Points outside the extent count for the nearest cell (dense: clamped onto the extent).
    const double px = std::clamp(train.x[i], c.extent[0], c.extent[1]);
    const double py = std::clamp(train.y[i], c.extent[2], c.extent[3]);
    const int home = map.CellIndex(px, py);
    if (!c.dense) {
      theta[static_cast<std::size_t>(home)].push_back(train.theta[i]);
      continue;
    }
    const int ix = home % c.cells_x, iy = home / c.cells_x;
    for (int jy = std::max(0, iy - map.window_y_);
         jy <= std::min(c.cells_y - 1, iy + map.window_y_); ++jy) {
      for (int jx = std::max(0, ix - map.window_x_);
           jx <= std::min(c.cells_x - 1, ix + map.window_x_); ++jx) {
        const int cell = jy * c.cells_x + jx;
        const Eigen::Vector2d centre = map.CellCentre(cell);
        const double dx = px - centre.x(), dy = py - centre.y();
        if (dx * dx + dy * dy <= r2)
          theta[static_cast<std::size_t>(cell)].push_back(train.theta[i]);
      }
    }
  }
  int empty = 0;
  for (int cell = 0; cell < cells; ++cell) {
    const auto& t = theta[static_cast<std::size_t>(cell)];
    map.counts_[static_cast<std::size_t>(cell)] = static_cast<int>(t.size());
    empty += t.empty();
    FitCell(t, c, c.seed ^ (0xD1B54A32D192ED03ull * (static_cast<std::uint64_t>(cell) + 1)),
            &map.cells_, cell);
  }
  log::Debug("directional grid map: ", c.cells_x, " x ", c.cells_y, " cells (", empty, " empty), ",
             c.kind == GridKind::kUnimodal ? "UM" : "MM", c.dense ? " dense" : "", " from ",
             train.size(), " samples");
  return map;
}

int GridMap::CellIndex(double x, double y) const {
  const auto& c = config_;
  const double fx = std::floor((x - c.extent[0]) / cell_w_),
               fy = std::floor((y - c.extent[2]) / cell_h_);
  const int ix = static_cast<int>(std::clamp(fx, 0.0, static_cast<double>(c.cells_x - 1)));
  const int iy = static_cast<int>(std::clamp(fy, 0.0, static_cast<double>(c.cells_y - 1)));
  return iy * c.cells_x + ix;
}

Eigen::Vector2d GridMap::CellCentre(int cell) const {
  const int ix = cell % config_.cells_x, iy = cell / config_.cells_x;
  return {config_.extent[0] + (ix + 0.5) * cell_w_, config_.extent[2] + (iy + 0.5) * cell_h_};
}

void GridMap::Query(const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& y, VonMisesMixtureBatch* out) const {
  FS_THROW_UNLESS(x.size() == y.size(), "directional grid map query: x [", x.size(), "] and y [",
                  y.size(), "] differ in size");
  const Eigen::Index n = x.size();
  const int r = cell_components();
  if (out->alpha.rows() != n || out->alpha.cols() != output_components() || out->mu.rows() != n ||
      out->mu.cols() != output_components() || out->kappa.rows() != n ||
      out->kappa.cols() != output_components())
    out->Resize(n, output_components());
  const auto& c = config_;
  for (Eigen::Index i = 0; i < n; ++i) {
    FS_THROW_UNLESS(std::isfinite(x[i]) && std::isfinite(y[i]),
                    "directional grid map query: point ", i, " (", x[i], ", ", y[i],
                    ") is not finite");
    const int home = CellIndex(x[i], y[i]);
    if (!c.dense) {
      out->alpha.row(i) = cells_.alpha.row(home);
      out->mu.row(i) = cells_.mu.row(home);
      out->kappa.row(i) = cells_.kappa.row(home);
      continue;
    }
    out->alpha.row(i).setZero();
    out->mu.row(i).setZero();
    out->kappa.row(i).setZero();
    const double qx = std::clamp(x[i], c.extent[0], c.extent[1]);
    const double qy = std::clamp(y[i], c.extent[2], c.extent[3]);
    const int ix = home % c.cells_x, iy = home / c.cells_x;
    const int y0 = std::max(0, iy - window_y_), y1 = std::min(c.cells_y - 1, iy + window_y_);
    const int x0 = std::max(0, ix - window_x_), x1 = std::min(c.cells_x - 1, ix + window_x_);
    auto dist2 = [&](int cell) {
      const Eigen::Vector2d centre = CellCentre(cell);
      return (qx - centre.x()) * (qx - centre.x()) + (qy - centre.y()) * (qy - centre.y());
    };
    // Pass 1: the nearest non-empty cell in reach (its weight is the largest; subtracting its
    // distance keeps the normalisation free of underflow for tiny length scales).
    double d2_min = std::numeric_limits<double>::infinity();
    for (int jy = y0; jy <= y1; ++jy)
      for (int jx = x0; jx <= x1; ++jx) {
        const int cell = jy * c.cells_x + jx;
        const double d2 = dist2(cell);
        if (counts_[static_cast<std::size_t>(cell)] > 0 && d2 <= radius_ * radius_)
          d2_min = std::min(d2_min, d2);
      }
    if (!std::isfinite(d2_min)) {
      out->alpha(i, 0) = 1.0;  // no data in reach: uniform
      continue;
    }
    const double inv = 1.0 / (2.0 * c.length_scale * c.length_scale);
    double total = 0;
    for (int pass = 0; pass < 2; ++pass) {
      Eigen::Index col = 0;
      for (int jy = y0; jy <= y1; ++jy)
        for (int jx = x0; jx <= x1; ++jx) {
          const int cell = jy * c.cells_x + jx;
          const double d2 = dist2(cell);
          if (counts_[static_cast<std::size_t>(cell)] == 0 || d2 > radius_ * radius_) continue;
          const double w = std::exp(-(d2 - d2_min) * inv);
          if (pass == 0) {
            total += w;
            continue;
          }
          out->alpha.row(i).segment(col, r) = cells_.alpha.row(cell) * (w / total);
          out->mu.row(i).segment(col, r) = cells_.mu.row(cell);
          out->kappa.row(i).segment(col, r) = cells_.kappa.row(cell);
          col += r;
        }
    }
  }
}

}  // namespace foresight::directional
