#include "models/occupancy/coupled_bhm.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "core/error.h"
#include "models/occupancy/fast_bhm.h"

namespace foresight::occupancy {
namespace {

double LogSigmoid(double z) {
  return z >= 0 ? -std::log1p(std::exp(-z)) : z - std::log1p(std::exp(z));
}

/// KL(N(mu, Sigma) || N(m0 1, s0 I)) from tr Sigma, mu and log det Sigma.
double GaussianKl(const Eigen::VectorXd& mu, double trace_sigma, double log_det_sigma, double m0,
                  double s0) {
  const double t = static_cast<double>(mu.size());
  return 0.5 * (trace_sigma / s0 + (mu.array() - m0).square().sum() / s0 - t + t * std::log(s0) -
                log_det_sigma);
}

}  // namespace

std::size_t SparseInformation::Bytes() const {
  return static_cast<std::size_t>(precision_data.nonZeros()) * (sizeof(double) + sizeof(int)) +
         static_cast<std::size_t>(precision_data.outerSize() + 1) * sizeof(int) +
         static_cast<std::size_t>(info_data.size()) * sizeof(double);
}

CoupledBhmLearner::CoupledBhmLearner(HingeGrid grid, const CoupledBhmOptions& options)
    : grid_(std::move(grid)), options_(options) {
  FS_THROW_UNLESS(options.prior_variance > 0 && std::isfinite(options.prior_variance),
                  "coupled BHM: prior_variance = ", options.prior_variance,
                  " must be positive and finite");
  FS_THROW_UNLESS(std::isfinite(options.prior_mean),
                  "coupled BHM: prior_mean = ", options.prior_mean, " must be finite");
  FS_THROW_UNLESS(options.elbo_tolerance >= 0,
                  "coupled BHM: elbo_tolerance = ", options.elbo_tolerance, " must be >= 0");
  stride_ = grid_.max_active();
  FS_THROW_UNLESS(stride_ <= 64 * 64, "coupled BHM: ", stride_,
                  " features per point exceed the 4096 the assembly buffers hold (",
                  grid_.Describe(), ")");
  mean_ = Eigen::VectorXd::Constant(grid_.size(), options.prior_mean);
  variance_ = Eigen::VectorXd::Constant(grid_.size(), options.prior_variance);
}

void CoupledBhmLearner::Add(const Eigen::Ref<const Eigen::Matrix2Xd>& xy,
                            const std::uint8_t* occupied) {
  const auto n = static_cast<std::size_t>(xy.cols());
  for (std::size_t i = 0; i < n; ++i) {
    FS_THROW_UNLESS(std::isfinite(xy(0, i)) && std::isfinite(xy(1, i)), "coupled BHM: added scan ",
                    scans_, " point ", i, " has a non-finite coordinate (", xy(0, i), ", ",
                    xy(1, i), ")");
  }
  FS_THROW_UNLESS(n == 0 || occupied != nullptr, "coupled BHM: scan ", scans_, " has ", n,
                  " points but no labels");
  const std::size_t first = labels_.size();
  labels_.resize(first + n);
  z_.resize(first + n, 1.0);
  std::vector<int> idx(stride_);
  std::vector<double> phi(stride_);
  for (std::size_t i = 0; i < n; ++i) {
    const int k = grid_.Features(xy(0, i), xy(1, i), idx.data(), phi.data());
    index_.insert(index_.end(), idx.begin(), idx.begin() + k);
    value_.insert(value_.end(), phi.begin(), phi.begin() + k);
    offset_.push_back(index_.size());
    labels_[first + i] = occupied[i] ? 1 : 0;
  }
  ++scans_;
  pattern_stale_ = true;
}

void CoupledBhmLearner::BuildPattern() {
  const int t_size = grid_.size(), nx = grid_.nx();
  const double s = grid_.config().spacing, reach = 2.0 * grid_.config().cutoff_radius;
  window_ = static_cast<int>(std::floor(reach / s + 1e-9));
  const int width = 2 * window_ + 1;
  // Offsets (dx, dy) with dy >= 0 (dx >= 0 when dy = 0), in increasing linear order.
  stencil_index_.assign(static_cast<std::size_t>(window_ + 1) * width, -1);
  std::vector<std::pair<int, int>> offsets;
  for (int dy = 0; dy <= window_; ++dy) {
    for (int dx = -window_; dx <= window_; ++dx) {
      if (dy == 0 && dx < 0) continue;
      if ((dx * dx + dy * dy) * s * s > reach * reach * (1 + 1e-9)) continue;
      stencil_index_[dy * width + dx + window_] = static_cast<int>(offsets.size());
      offsets.emplace_back(dx, dy);
    }
  }
  stencil_size_ = static_cast<int>(offsets.size());
  std::vector<std::uint8_t> touched(t_size, 0);
  for (const int t : index_) touched[t] = 1;
  // Columns: the diagonal, then rows col + dy nx + dx in increasing order (offsets are sorted
  // by dy, then dx, i.e. by row index).
  const int k = stencil_size_;
  column_slot_.assign(static_cast<std::size_t>(t_size) * k, -1);
  std::vector<int> outer(t_size + 1, 0), inner;
  inner.reserve(static_cast<std::size_t>(t_size) * 4);
  for (int c = 0; c < t_size; ++c) {
    const int cx = c % nx, cy = c / nx;
    for (int o = 0; o < k; ++o) {
      const int rx = cx + offsets[o].first, ry = cy + offsets[o].second;
      if (rx < 0 || rx >= nx || ry >= grid_.ny()) continue;
      const int r = ry * nx + rx;
      if (o > 0 && !(touched[c] && touched[r])) continue;
      column_slot_[static_cast<std::size_t>(c) * k + o] = static_cast<int>(inner.size());
      inner.push_back(r);
    }
    outer[c + 1] = static_cast<int>(inner.size());
  }
  precision_ = Eigen::SparseMatrix<double>(t_size, t_size);
  precision_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), precision_.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), precision_.innerIndexPtr());
  std::fill(precision_.valuePtr(), precision_.valuePtr() + inner.size(), 1.0);
  data_values_.assign(inner.size(), 0.0);
  sigma_values_.assign(inner.size(), 0.0);
  // Every pair of features of one point has a slot: both centres lie within cutoff_radius of the
  // point, so they are at most 2 cutoff_radius apart (the stencil, with a 1e-9 relative margin
  // for rounding), and the point touches both.
  llt_.analyzePattern(precision_);
  sigma_slot_.clear();  // filled after the first factorisation (the pattern of L is known then)
  pattern_stale_ = false;
}

void CoupledBhmLearner::Assemble() {
  const int nx = grid_.nx(), width = 2 * window_ + 1, k = stencil_size_;
  std::fill(data_values_.begin(), data_values_.end(), 0.0);
  info_data_ = Eigen::VectorXd::Zero(grid_.size());
  int cx[64 * 64], cy[64 * 64];
  double* dv = data_values_.data();
  for (std::size_t p = 0; p < labels_.size(); ++p) {
    const int* idx = &index_[offset_[p]];
    const double* phi = &value_[offset_[p]];
    const int m = static_cast<int>(offset_[p + 1] - offset_[p]);
    const double two_lambda = 2.0 * JaakkolaLambda(z_[p]);
    const double target = labels_[p] ? 0.5 : -0.5;
    for (int a = 0; a < m; ++a) {
      cx[a] = idx[a] % nx;
      cy[a] = idx[a] / nx;
    }
    for (int a = 0; a < m; ++a) {
      info_data_[idx[a]] += target * phi[a];
      const double wa = two_lambda * phi[a];
      const int* col = &column_slot_[static_cast<std::size_t>(idx[a]) * k];
      dv[col[0]] += wa * phi[a];
      for (int b = a + 1; b < m; ++b) {
        const int o = stencil_index_[(cy[b] - cy[a]) * width + cx[b] - cx[a] + window_];
        dv[col[o]] += wa * phi[b];
      }
    }
  }
}

double CoupledBhmLearner::EStep() {
  Assemble();
  const int t_size = grid_.size(), k = stencil_size_;
  const double s0 = options_.prior_variance, m0 = options_.prior_mean;
  double* pv = precision_.valuePtr();
  std::copy(data_values_.begin(), data_values_.end(), pv);
  for (int t = 0; t < t_size; ++t) pv[column_slot_[static_cast<std::size_t>(t) * k]] += 1.0 / s0;
  llt_.factorize(precision_);
  FS_THROW_UNLESS(
      llt_.info() == Eigen::Success,
      "coupled BHM: the posterior precision is not positive definite (prior_variance = ", s0, ")");
  mean_ = llt_.solve((info_data_.array() + m0 / s0).matrix());
  inverter_.Compute(llt_);
  if (sigma_slot_.empty()) {
    sigma_slot_.resize(data_values_.size());
    for (int c = 0; c < t_size; ++c) {
      for (int q = precision_.outerIndexPtr()[c]; q < precision_.outerIndexPtr()[c + 1]; ++q) {
        sigma_slot_[q] = inverter_.Slot(precision_.innerIndexPtr()[q], c);
        FS_THROW_UNLESS(sigma_slot_[q] >= 0, "coupled BHM: entry (", precision_.innerIndexPtr()[q],
                        ", ", c, ") is missing from the factor's pattern (internal error)");
      }
    }
  }
  const std::vector<double>& zv = inverter_.values();
  for (std::size_t q = 0; q < sigma_slot_.size(); ++q) sigma_values_[q] = zv[sigma_slot_[q]];
  variance_.resize(t_size);
  for (int t = 0; t < t_size; ++t)
    variance_[t] = sigma_values_[column_slot_[static_cast<std::size_t>(t) * k]];
  // Per-point moments of f_n = phi_n . w and the expected log bound.
  const int nx = grid_.nx(), width = 2 * window_ + 1;
  quad_.resize(labels_.size());
  proj_.resize(labels_.size());
  int cx[64 * 64], cy[64 * 64];
  double data_term = 0;
  for (std::size_t p = 0; p < labels_.size(); ++p) {
    const int* idx = &index_[offset_[p]];
    const double* phi = &value_[offset_[p]];
    const int m = static_cast<int>(offset_[p + 1] - offset_[p]);
    for (int a = 0; a < m; ++a) {
      cx[a] = idx[a] % nx;
      cy[a] = idx[a] / nx;
    }
    double quad = 0, proj = 0;
    for (int a = 0; a < m; ++a) {
      proj += phi[a] * mean_[idx[a]];
      const int* col = &column_slot_[static_cast<std::size_t>(idx[a]) * k];
      double row = 0.5 * phi[a] * sigma_values_[col[0]];
      for (int b = a + 1; b < m; ++b) {
        const int o = stencil_index_[(cy[b] - cy[a]) * width + cx[b] - cx[a] + window_];
        row += phi[b] * sigma_values_[col[o]];
      }
      quad += 2.0 * phi[a] * row;
    }
    quad_[p] = quad;
    proj_[p] = proj;
    const double z = z_[p];
    data_term += LogSigmoid(z) - 0.5 * z - JaakkolaLambda(z) * (quad + proj * proj - z * z) +
                 (labels_[p] ? 0.5 : -0.5) * proj;
  }
  return data_term - GaussianKl(mean_, variance_.sum(), -inverter_.LogDetA(), m0, s0);
}

void CoupledBhmLearner::MStep(double* mean_abs_dz) {
  double total = 0;
  for (std::size_t p = 0; p < z_.size(); ++p) {
    const double z = std::sqrt(std::max(0.0, quad_[p]) + proj_[p] * proj_[p]);
    total += std::abs(z - z_[p]);
    z_[p] = z;
  }
  *mean_abs_dz = z_.empty() ? 0.0 : total / static_cast<double>(z_.size());
}

std::vector<BoundUpdateReport> CoupledBhmLearner::Fit(int bound_updates) {
  FS_THROW_UNLESS(bound_updates >= 0, "coupled BHM: bound_updates = ", bound_updates,
                  " must be >= 0");
  FS_THROW_UNLESS(points() > 0, "coupled BHM: Fit() needs points; call Add() first");
  using Clock = std::chrono::steady_clock;
  std::vector<BoundUpdateReport> reports;
  auto start = Clock::now();
  if (pattern_stale_) BuildPattern();
  for (int u = 0; u <= bound_updates; ++u) {
    BoundUpdateReport r;
    r.update = u;
    if (u > 0) {
      start = Clock::now();
      MStep(&r.mean_abs_dz);
    }
    r.elbo = EStep();
    r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (u > 0) {
      const double previous = reports.back().elbo;
      FS_THROW_UNLESS(r.elbo >= previous - options_.elbo_tolerance * std::abs(previous),
                      "coupled BHM: the ELBO decreased at bound update ", u, " from ", previous,
                      " to ", r.elbo, " (relative tolerance ", options_.elbo_tolerance, ")");
    }
    elbo_ = r.elbo;
    fitted_ = true;
    reports.push_back(r);
  }
  return reports;
}

double CoupledBhmLearner::Elbo() const {
  FS_THROW_UNLESS(fitted_, "coupled BHM: no ELBO before the first Fit()");
  return elbo_;
}

HingeMap CoupledBhmLearner::ToMap() const {
  HingeWeights w;
  w.mean = mean_;
  w.variance = variance_;
  return HingeMap(HingeMapKind::kFastBhm, grid_, std::move(w), options_.prior_mean,
                  options_.prior_variance);
}

SparseInformation CoupledBhmLearner::DataInformation() const {
  SparseInformation info;
  info.features = grid_.size();
  info.grid = grid_.config();
  FS_THROW_UNLESS(fitted_ && !pattern_stale_,
                  "coupled BHM: DataInformation() needs a Fit() after the last Add() (the data "
                  "terms are assembled by the E-step)");
  info.precision_data = precision_;
  std::copy(data_values_.begin(), data_values_.end(), info.precision_data.valuePtr());
  info.info_data = info_data_;
  // data_values_ were assembled at the bounds of the last E-step; later M-steps do not happen
  // without an E-step, so they are the current bounds.
  return info;
}

HingeMap CoupledBhmLearner::FuseInformation(const HingeGrid& grid, const CoupledBhmOptions& options,
                                            const std::vector<SparseInformation>& parts) {
  const int t_size = grid.size();
  FS_THROW_UNLESS(options.prior_variance > 0,
                  "coupled BHM fusion: prior_variance = ", options.prior_variance,
                  " must be positive");
  Eigen::SparseMatrix<double> p(t_size, t_size);
  Eigen::VectorXd b =
      Eigen::VectorXd::Constant(t_size, options.prior_mean / options.prior_variance);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const SparseInformation& part = parts[i];
    FS_THROW_UNLESS(part.features == t_size && part.precision_data.rows() == t_size &&
                        part.precision_data.cols() == t_size && part.info_data.size() == t_size,
                    "coupled BHM fusion: part ", i, " has ", part.features, " features (precision ",
                    part.precision_data.rows(), " x ", part.precision_data.cols(), ", information ",
                    part.info_data.size(), "), the grid ", grid.Describe(), " has ", t_size);
    FS_THROW_UNLESS(grid.SameFeatures(HingeGrid(part.grid)), "coupled BHM fusion: part ", i,
                    " was learned on the grid ", HingeGrid(part.grid).Describe(), ", not ",
                    grid.Describe());
    p += part.precision_data;
    b += part.info_data;
  }
  Eigen::SparseMatrix<double> prior(t_size, t_size);
  prior.setIdentity();
  p += prior / options.prior_variance;
  p.makeCompressed();
  SparseCholesky llt(p);
  FS_THROW_UNLESS(llt.info() == Eigen::Success,
                  "coupled BHM fusion: the fused precision is not positive definite");
  SelectedInverter inverter;
  inverter.Compute(llt);
  HingeWeights w;
  w.mean = llt.solve(b);
  w.variance.resize(t_size);
  for (int t = 0; t < t_size; ++t) w.variance[t] = inverter.Diagonal(t);
  return HingeMap(HingeMapKind::kFastBhm, grid, std::move(w), options.prior_mean,
                  options.prior_variance);
}

}  // namespace foresight::occupancy
