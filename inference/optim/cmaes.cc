#include "inference/optim/cmaes.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace foresight::optim {

namespace {

bool AllFinite(const Eigen::MatrixXd& a) { return a.allFinite(); }

template <typename T>
std::string Describe(const char* field, const T& value, const char* expectation) {
  return internal::Concat("CmaEsOptions.", field, " = ", value, " ", expectation);
}

}  // namespace

const char* ToString(CmaEsStatus status) {
  switch (status) {
    case CmaEsStatus::kRunning:
      return "running";
    case CmaEsStatus::kTargetReached:
      return "target_reached";
    case CmaEsStatus::kMaxEvaluations:
      return "max_evaluations";
    case CmaEsStatus::kTolFun:
      return "tol_fun";
    case CmaEsStatus::kTolX:
      return "tol_x";
    case CmaEsStatus::kConditionCov:
      return "condition_cov";
    case CmaEsStatus::kNoEffect:
      return "no_effect";
    case CmaEsStatus::kNonFiniteCosts:
      return "non_finite_costs";
    case CmaEsStatus::kNumericalError:
      return "numerical_error";
  }
  return "";
}

bool CmaEsOptions::IsValid(std::string* error) const {
  std::string message;
  if (population != 0 && population < 2) {
    message = Describe("population", population, "must be 0 (default) or >= 2");
  } else if (!(std::isfinite(sigma0) && sigma0 > 0)) {
    message = Describe("sigma0", sigma0, "must be finite and > 0");
  } else if (lower.size() != upper.size()) {
    message = internal::Concat("CmaEsOptions.lower has size ", lower.size(),
                               " but CmaEsOptions.upper has size ", upper.size(),
                               "; both must be empty or of the dimension");
  } else if (max_evaluations < 0) {
    message = Describe("max_evaluations", max_evaluations, "must be >= 0 (0: 1000 n^2)");
  } else if (std::isnan(target_cost)) {
    message = Describe("target_cost", target_cost, "must not be NaN");
  } else if (!(std::isfinite(tol_fun) && tol_fun >= 0)) {
    message = Describe("tol_fun", tol_fun, "must be finite and >= 0");
  } else if (!(std::isfinite(tol_x) && tol_x >= 0)) {
    message = Describe("tol_x", tol_x, "must be finite and >= 0");
  } else if (!(max_condition > 1)) {
    message = Describe("max_condition", max_condition, "must be > 1");
  } else {
    for (Eigen::Index i = 0; i < lower.size(); ++i) {
      if (std::isnan(lower[i]) || std::isnan(upper[i]) || lower[i] > upper[i] ||
          lower[i] == std::numeric_limits<double>::infinity() ||
          upper[i] == -std::numeric_limits<double>::infinity()) {
        message = internal::Concat("CmaEsOptions.lower[", i, "] = ", lower[i],
                                   " and CmaEsOptions.upper[", i, "] = ", upper[i],
                                   " do not form an interval (need lower <= upper, no NaN)");
        break;
      }
    }
  }
  if (message.empty()) return true;
  if (error != nullptr) *error = message;
  return false;
}

CmaEsParameters MakeCmaEsParameters(int n, int lambda) {
  FS_THROW_UNLESS(n >= 1, "CMA-ES dimension n = ", n, " must be >= 1");
  FS_THROW_UNLESS(lambda == 0 || lambda >= 2, "CMA-ES population lambda = ", lambda,
                  " must be 0 (default) or >= 2");
  CmaEsParameters p;
  const double dn = n;
  p.n = n;
  // (48)
  p.lambda = lambda > 0 ? lambda : 4 + static_cast<int>(std::floor(3.0 * std::log(dn)));
  p.mu = p.lambda / 2;
  // (49): w'_i = ln((lambda + 1) / 2) - ln i; the first mu are positive and normalised to sum 1
  // (positive weights only: the negative weights of (53) are not used).
  p.weights.resize(p.mu);
  for (int i = 0; i < p.mu; ++i) p.weights[i] = std::log((p.lambda + 1) / 2.0) - std::log(i + 1.0);
  p.weights /= p.weights.sum();
  p.mu_eff = 1.0 / p.weights.squaredNorm();
  const double mu_eff = p.mu_eff;
  p.c_m = 1.0;                                       // (54)
  p.c_sigma = (mu_eff + 2.0) / (dn + mu_eff + 5.0);  // (55)
  p.d_sigma = 1.0 + 2.0 * std::max(0.0, std::sqrt((mu_eff - 1.0) / (dn + 1.0)) - 1.0) + p.c_sigma;
  p.c_c = (4.0 + mu_eff / dn) / (dn + 4.0 + 2.0 * mu_eff / dn);  // (56)
  const double alpha_cov = 2.0;
  p.c_1 = alpha_cov / ((dn + 1.3) * (dn + 1.3) + mu_eff);  // (57)
  // (58) as printed in the 2016 tutorial (later revisions add 1/4 to the numerator's mu_eff term).
  p.c_mu = std::min(1.0 - p.c_1, alpha_cov * (mu_eff - 2.0 + 1.0 / mu_eff) /
                                     ((dn + 2.0) * (dn + 2.0) + alpha_cov * mu_eff / 2.0));
  // E||N(0, I)||, the approximation used with (44).
  p.chi_n = std::sqrt(dn) * (1.0 - 1.0 / (4.0 * dn) + 1.0 / (21.0 * dn * dn));
  // App. B.2 / App. C: decompose C when more than lambda / (c_1 + c_mu) / n / 10 evaluations
  // passed since the last decomposition (O(n^2) work per evaluation on average).
  p.eigen_interval = p.lambda / (p.c_1 + p.c_mu) / dn / 10.0;
  // Hansen 2011, injection clip length.
  p.c_y = std::sqrt(dn) + 2.0 * dn / (dn + 2.0);
  return p;
}

CmaEs::CmaEs(const Eigen::VectorXd& mean0, const CmaEsOptions& options)
    : options_(options), rng_(options.seed) {
  std::string error;
  FS_THROW_UNLESS(options.IsValid(&error), error);
  const Eigen::Index n = mean0.size();
  FS_THROW_UNLESS(n >= 1, "CmaEs: mean0 is empty (the dimension n must be >= 1)");
  for (Eigen::Index i = 0; i < n; ++i)
    FS_THROW_UNLESS(std::isfinite(mean0[i]), "CmaEs: mean0[", i, "] = ", mean0[i],
                    " is not finite");
  bounded_ = options.lower.size() > 0;
  if (bounded_) {
    FS_THROW_UNLESS(options.lower.size() == n, "CmaEsOptions.lower has size ", options.lower.size(),
                    " but mean0 has dimension n = ", n, " (bounds must be empty or of size n)");
    for (Eigen::Index i = 0; i < n; ++i)
      FS_THROW_UNLESS(options.lower[i] <= mean0[i] && mean0[i] <= options.upper[i], "CmaEs: mean0[",
                      i, "] = ", mean0[i], " is outside the bounds [", options.lower[i], ", ",
                      options.upper[i], "]");
  }
  FS_THROW_UNLESS(std::isfinite(mean0.cwiseAbs().maxCoeff() + 1e4 * options.sigma0),
                  "CmaEsOptions.sigma0 = ", options.sigma0,
                  " is too large: samples would overflow double");
  params_ = MakeCmaEsParameters(static_cast<int>(n), options.population);
  max_evaluations_ = options.max_evaluations > 0 ? options.max_evaluations
                                                 : static_cast<std::int64_t>(1000) * n * n;
  const int lambda = params_.lambda;

  // Fig. 6 initialisation: p_sigma = p_c = 0, C = I, m and sigma given.
  mean_ = mean0;
  sigma_ = options.sigma0;
  p_sigma_ = Eigen::VectorXd::Zero(n);
  p_c_ = Eigen::VectorXd::Zero(n);
  C_ = Eigen::MatrixXd::Identity(n, n);
  B_ = Eigen::MatrixXd::Identity(n, n);
  inv_sqrt_C_ = Eigen::MatrixXd::Identity(n, n);
  D_ = Eigen::VectorXd::Ones(n);

  X_.resize(n, lambda);
  X_raw_.resize(n, lambda);
  Y_.resize(n, lambda);
  injected_.resize(n, 0);
  order_.resize(lambda);
  ranked_costs_.resize(lambda);
  gamma_ = Eigen::VectorXd::Ones(n);  // replaced by 2 delta_fit after the first generation
  best_x_ = mean0;
}

double CmaEs::condition() const {
  const double d_max = D_.maxCoeff(), d_min = D_.minCoeff();
  return (d_max / d_min) * (d_max / d_min);
}

Eigen::VectorXd CmaEs::Repair(const Eigen::VectorXd& x) const {
  if (!bounded_) return x;
  return x.cwiseMax(options_.lower).cwiseMin(options_.upper);
}

void CmaEs::Inject(const Eigen::MatrixXd& candidates) {
  FS_THROW_UNLESS(status_ == CmaEsStatus::kRunning, "CmaEs::Inject: the run has stopped (status ",
                  ToString(status_), ")");
  FS_THROW_UNLESS(!asked_, "CmaEs::Inject after Ask: the batch of generation ", generation_,
                  " was already sampled; Tell its costs first");
  FS_THROW_UNLESS(candidates.rows() == params_.n, "CmaEs::Inject: candidates has ",
                  candidates.rows(), " rows, expected the dimension n = ", params_.n);
  FS_THROW_UNLESS(candidates.cols() >= 1 && candidates.cols() <= params_.lambda,
                  "CmaEs::Inject: candidates has ", candidates.cols(),
                  " columns, expected 1..lambda = ", params_.lambda);
  for (Eigen::Index k = 0; k < candidates.cols(); ++k)
    for (Eigen::Index i = 0; i < candidates.rows(); ++i)
      FS_THROW_UNLESS(std::isfinite(candidates(i, k)), "CmaEs::Inject: candidates(", i, ", ", k,
                      ") = ", candidates(i, k), " is not finite");
  injected_ = candidates;
}

const Eigen::MatrixXd& CmaEs::Ask() {
  FS_THROW_UNLESS(status_ == CmaEsStatus::kRunning, "CmaEs::Ask: the run has stopped (status ",
                  ToString(status_), "); construct a new CmaEs to restart");
  if (asked_) return X_;
  const int n = params_.n;
  const Eigen::Index injected = injected_.cols();
  Eigen::VectorXd z(n);
  for (int k = 0; k < params_.lambda; ++k) {
    if (k < injected) {
      // Hansen 2011: the injected point is evaluated as given (here: projected onto the box); its
      // step enters the update clipped to Mahalanobis length c_y.
      X_.col(k) = Repair(injected_.col(k));
      X_raw_.col(k) = X_.col(k);
      Y_.col(k) = (X_.col(k) - mean_) / sigma_;
      const double length = (inv_sqrt_C_ * Y_.col(k)).norm();
      if (length > params_.c_y) Y_.col(k) *= params_.c_y / length;
    } else {
      for (int i = 0; i < n; ++i) z[i] = normal_(rng_);  // (38)
      Y_.col(k) = B_ * D_.cwiseProduct(z);               // (39)
      X_raw_.col(k) = mean_ + sigma_ * Y_.col(k);        // (40)
      X_.col(k) = Repair(X_raw_.col(k));
    }
  }
  injected_.resize(n, 0);
  asked_ = true;
  return X_;
}

void CmaEs::UpdateBoundWeights(const Eigen::VectorXd& costs) {
  const int n = params_.n;
  const double mean_variance = sigma_ * sigma_ * C_.diagonal().mean();
  // Interquartile range of this generation's (finite) costs, per unit of variance.
  std::vector<double> finite;
  finite.reserve(costs.size());
  for (Eigen::Index k = 0; k < costs.size(); ++k)
    if (std::isfinite(costs[k])) finite.push_back(costs[k]);
  std::sort(finite.begin(), finite.end());
  if (finite.size() >= 2) {
    const std::size_t l = finite.size() + 1;
    const double iqr =
        (finite[std::min(finite.size() - 1, 3 * l / 4)] - finite[l / 4]) / mean_variance;
    if (std::isfinite(iqr) && iqr > 0) {
      iqr_history_.insert(iqr_history_.begin(), iqr);
      const std::size_t keep = 20 + static_cast<std::size_t>(3 * n / params_.lambda);
      if (iqr_history_.size() > keep) iqr_history_.resize(keep);
    }
  }
  const Eigen::VectorXd repaired_mean = Repair(mean_);
  const bool mean_outside = (repaired_mean.array() != mean_.array()).any();
  if (!gamma_adapting_) {
    if (!iqr_history_.empty()) {
      std::vector<double> sorted = iqr_history_;
      std::sort(sorted.begin(), sorted.end());
      const std::size_t m = sorted.size();
      const double delta_fit =
          m % 2 == 1 ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
      gamma_.setConstant(2.0 * delta_fit);
    }
    gamma_adapting_ = mean_outside;
    return;
  }
  const double tolerance = 3.0 * std::max(1.0, std::sqrt(static_cast<double>(n)) / params_.mu_eff);
  const double factor = std::pow(1.1, std::min(1.0, params_.mu_eff / (10.0 * n)));
  for (int i = 0; i < n; ++i) {
    const double violation = std::abs(mean_[i] - repaired_mean[i]) / (sigma_ * std::sqrt(C_(i, i)));
    if (violation > tolerance) gamma_[i] *= factor;
  }
}

void CmaEs::Decompose(bool* ok) {
  // C kept exactly symmetric before the decomposition (rounding in the rank-mu product).
  C_ = (0.5 * (C_ + C_.transpose())).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(C_);
  *ok = solver.info() == Eigen::Success && AllFinite(solver.eigenvalues()) &&
        solver.eigenvalues().minCoeff() > 0;
  if (!*ok) return;
  B_ = solver.eigenvectors();
  D_ = solver.eigenvalues().cwiseSqrt();
  inv_sqrt_C_ = B_ * D_.cwiseInverse().asDiagonal() * B_.transpose();
  eigen_evaluations_ = evaluations_;
}

CmaEsStatus CmaEs::Tell(const Eigen::VectorXd& costs) {
  FS_THROW_UNLESS(status_ == CmaEsStatus::kRunning, "CmaEs::Tell: the run has stopped (status ",
                  ToString(status_), ")");
  FS_THROW_UNLESS(asked_, "CmaEs::Tell called before Ask: no batch is pending (generation ",
                  generation_, ")");
  FS_THROW_UNLESS(costs.size() == params_.lambda, "CmaEs::Tell: costs has size ", costs.size(),
                  ", expected the population lambda = ", params_.lambda);
  const int n = params_.n, lambda = params_.lambda, mu = params_.mu;
  const CmaEsParameters& p = params_;
  asked_ = false;
  evaluations_ += lambda;
  ++generation_;

  int finite = 0;
  for (int k = 0; k < lambda; ++k) {
    if (!std::isfinite(costs[k])) {
      ++non_finite_costs_;
      continue;
    }
    ++finite;
    if (costs[k] < best_cost_) {
      best_cost_ = costs[k];
      best_x_ = X_.col(k);
    }
  }
  if (finite == 0) {
    status_ = CmaEsStatus::kNonFiniteCosts;
    return status_;
  }

  // Ranking values: non-finite costs rank last; out-of-box samples are penalised (Hansen 2009).
  const double inf = std::numeric_limits<double>::infinity();
  if (bounded_) UpdateBoundWeights(costs);
  for (int k = 0; k < lambda; ++k) {
    ranked_costs_[k] = std::isfinite(costs[k]) ? costs[k] : inf;
    if (bounded_ && std::isfinite(costs[k]))
      ranked_costs_[k] += (gamma_.array() * (X_raw_.col(k) - X_.col(k)).array().square()).sum() / n;
  }
  for (int k = 0; k < lambda; ++k) order_[k] = k;
  std::sort(order_.begin(), order_.end(), [this](int a, int b) {
    return ranked_costs_[a] < ranked_costs_[b] || (ranked_costs_[a] == ranked_costs_[b] && a < b);
  });

  // Keep the last good state: an update that turns out non-finite is discarded.
  const Eigen::VectorXd old_mean = mean_, old_p_sigma = p_sigma_, old_p_c = p_c_;
  const Eigen::MatrixXd old_C = C_;
  const double old_sigma = sigma_;

  // (41) <y>_w = sum_{i<=mu} w_i y_{i:lambda}; (42) m <- m + c_m sigma <y>_w.
  Eigen::VectorXd y_w = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < mu; ++i) y_w += p.weights[i] * Y_.col(order_[i]);
  mean_ += p.c_m * sigma_ * y_w;
  // (43) p_sigma <- (1 - c_sigma) p_sigma + sqrt(c_sigma (2 - c_sigma) mu_eff) C^{-1/2} <y>_w.
  p_sigma_ = (1.0 - p.c_sigma) * p_sigma_ +
             std::sqrt(p.c_sigma * (2.0 - p.c_sigma) * p.mu_eff) * (inv_sqrt_C_ * y_w);
  // (44) sigma <- sigma exp(c_sigma / d_sigma (||p_sigma|| / E||N(0, I)|| - 1)).
  const double p_sigma_norm = p_sigma_.norm();
  sigma_ *= std::exp(p.c_sigma / p.d_sigma * (p_sigma_norm / p.chi_n - 1.0));
  // h_sigma (after (45)): 1 if ||p_sigma|| / sqrt(1 - (1 - c_sigma)^(2(g+1))) < (1.4 + 2/(n+1))
  // E||N(0, I)||, with g + 1 = generations completed.
  const double h_sigma =
      p_sigma_norm / std::sqrt(1.0 - std::pow(1.0 - p.c_sigma, 2.0 * generation_)) <
              (1.4 + 2.0 / (n + 1.0)) * p.chi_n
          ? 1.0
          : 0.0;
  // (45) p_c <- (1 - c_c) p_c + h_sigma sqrt(c_c (2 - c_c) mu_eff) <y>_w.
  p_c_ = (1.0 - p.c_c) * p_c_ + h_sigma * std::sqrt(p.c_c * (2.0 - p.c_c) * p.mu_eff) * y_w;
  // (47) with positive weights (sum w_j = 1, so w_i° = w_i of (46)):
  // C <- (1 + c_1 delta(h_sigma) - c_1 - c_mu) C + c_1 p_c p_c^T + c_mu sum w_i y_i y_i^T,
  // delta(h_sigma) = (1 - h_sigma) c_c (2 - c_c).
  const double delta_h = (1.0 - h_sigma) * p.c_c * (2.0 - p.c_c);
  C_ *= 1.0 + p.c_1 * delta_h - p.c_1 - p.c_mu;
  C_.noalias() += p.c_1 * p_c_ * p_c_.transpose();
  for (int i = 0; i < mu; ++i)
    C_.noalias() += (p.c_mu * p.weights[i]) * Y_.col(order_[i]) * Y_.col(order_[i]).transpose();

  // App. B.4 flat fitness: if the best and the ceil(0.7 lambda)-th ranked values are equal, the
  // ranking carries no information about the scale; increase sigma.
  const int flat_rank = static_cast<int>(std::ceil(0.7 * lambda)) - 1;
  if (ranked_costs_[order_[0]] == ranked_costs_[order_[flat_rank]]) {
    sigma_ *= std::exp(0.2 + p.c_sigma / p.d_sigma);
    ++flat_generations_;
  }

  // Numeric guard: everything finite, sigma > 0 and samples m + sigma y representable.
  bool ok = AllFinite(mean_) && AllFinite(p_sigma_) && AllFinite(p_c_) && AllFinite(C_) &&
            std::isfinite(sigma_) && sigma_ > 0 &&
            std::isfinite(mean_.cwiseAbs().maxCoeff() +
                          1e4 * sigma_ * std::sqrt(n * C_.diagonal().cwiseAbs().maxCoeff()));
  if (ok && evaluations_ - eigen_evaluations_ > p.eigen_interval) Decompose(&ok);
  if (!ok) {
    mean_ = old_mean;
    p_sigma_ = old_p_sigma;
    p_c_ = old_p_c;
    C_ = old_C;
    sigma_ = old_sigma;
    status_ = CmaEsStatus::kNumericalError;
    return status_;
  }
  status_ = CheckStop();
  return status_;
}

CmaEsStatus CmaEs::CheckStop() {
  const int n = params_.n, lambda = params_.lambda;
  if (best_cost_ <= options_.target_cost) return CmaEsStatus::kTargetReached;
  if (evaluations_ + lambda > max_evaluations_) return CmaEsStatus::kMaxEvaluations;

  // TolFun: range of the best values of the last 10 + ceil(30 n / lambda) generations and of all
  // values of the last generation.
  const std::size_t window = 10 + static_cast<std::size_t>(std::ceil(30.0 * n / lambda));
  best_history_.insert(best_history_.begin(), ranked_costs_[order_[0]]);
  if (best_history_.size() > window) best_history_.resize(window);
  if (best_history_.size() == window && options_.tol_fun > 0) {
    double lo = ranked_costs_.minCoeff(), hi = ranked_costs_.maxCoeff();
    for (double v : best_history_) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (hi - lo < options_.tol_fun) return CmaEsStatus::kTolFun;
  }

  // TolX: all coordinate standard deviations and sigma p_c below tol_x sigma0.
  const double tol_x = options_.tol_x * options_.sigma0;
  if (tol_x > 0 && (sigma_ * C_.diagonal().cwiseSqrt().array() < tol_x).all() &&
      (sigma_ * p_c_.cwiseAbs().array() < tol_x).all())
    return CmaEsStatus::kTolX;

  if (condition() > options_.max_condition) return CmaEsStatus::kConditionCov;

  // NoEffectAxis: a 0.1-standard-deviation step along a principal axis leaves m unchanged;
  // NoEffectCoord: a 0.2-standard-deviation step in a coordinate leaves m_i unchanged.
  for (int i = 0; i < n; ++i) {
    if ((mean_ + 0.1 * sigma_ * D_[i] * B_.col(i)).cwiseEqual(mean_).all())
      return CmaEsStatus::kNoEffect;
    if (mean_[i] + 0.2 * sigma_ * std::sqrt(C_(i, i)) == mean_[i]) return CmaEsStatus::kNoEffect;
  }
  return CmaEsStatus::kRunning;
}

std::string CmaEsSummary::BriefReport() const {
  std::ostringstream os;
  os << "CMA-ES " << ToString(status) << ": best cost " << best_cost << " after " << evaluations
     << " evaluations (" << generations << " generations), " << non_finite_costs
     << " non-finite costs, final sigma " << final_sigma;
  return os.str();
}

CmaEsSummary Minimize(const std::function<double(const Eigen::VectorXd&)>& f,
                      const Eigen::VectorXd& x0, const CmaEsOptions& options) {
  FS_THROW_UNLESS(static_cast<bool>(f), "Minimize: the cost function is empty");
  CmaEs es(x0, options);
  Eigen::VectorXd costs(es.population());
  while (es.status() == CmaEsStatus::kRunning) {
    const Eigen::MatrixXd& X = es.Ask();
    for (Eigen::Index k = 0; k < X.cols(); ++k) costs[k] = f(X.col(k));
    es.Tell(costs);
  }
  CmaEsSummary summary;
  summary.status = es.status();
  summary.best_x = es.best_x();
  summary.best_cost = es.best_cost();
  summary.evaluations = es.evaluations();
  summary.generations = es.generation();
  summary.non_finite_costs = es.non_finite_costs();
  summary.final_sigma = es.sigma();
  return summary;
}

}  // namespace foresight::optim
