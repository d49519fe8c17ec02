#include "models/imitation/occupancy_fit.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <memory>
#include <unordered_map>

#include "core/error.h"

namespace foresight::imitation {
namespace {

constexpr int kMaxNewtonIterations = 100;
constexpr long kMaxSamples = 10000000;

// log(1 + exp(f)) without overflow.
double Softplus(double f) { return f > 0 ? f + std::log1p(std::exp(-f)) : std::log1p(std::exp(f)); }
double Sigmoid(double f) {
  if (f >= 0) return 1.0 / (1.0 + std::exp(-f));
  const double e = std::exp(f);
  return e / (1.0 + e);
}

// The samples' features in compressed rows over the active states (local indices 0..m-1).
struct SparseFeatures {
  std::vector<int> start{0}, column;
  std::vector<double> value;
  int active = 0;
};

// f_i = b + sum_k phi_ik w_k for all samples.
void Latent(const SparseFeatures& x, const Eigen::VectorXd& w, double b, Eigen::VectorXd* f) {
  const long n = static_cast<long>(x.start.size()) - 1;
  for (long i = 0; i < n; ++i) {
    double s = b;
    for (int k = x.start[i]; k < x.start[i + 1]; ++k) s += x.value[k] * w[x.column[k]];
    (*f)[i] = s;
  }
}

double Loss(const Eigen::VectorXd& f, const Eigen::VectorXd& y, const Eigen::VectorXd& w,
            double l2) {
  double loss = 0.5 * l2 * w.squaredNorm();
  for (Eigen::Index i = 0; i < f.size(); ++i) loss += Softplus(f[i]) - y[i] * f[i];
  return loss;
}

}  // namespace

template <int D>
OccupancyField<D> FitOccupancyField(const RbfGrid<D>& grid,
                                    const Eigen::Matrix<double, D, Eigen::Dynamic>& points,
                                    const std::vector<std::uint8_t>& occupied, double l2,
                                    const std::string& source) {
  const long n = points.cols();
  FS_THROW_UNLESS(static_cast<long>(occupied.size()) == n, source, ": ", n, " points but ",
                  occupied.size(), " occupancy labels");
  FS_THROW_UNLESS(n > 0, source, ": no occupancy samples");
  FS_THROW_UNLESS(points.allFinite(), source, ": occupancy sample points are not finite");
  FS_THROW_UNLESS(std::isfinite(l2) && l2 > 0, source, ": l2 penalty ", l2,
                  " must be positive and finite");
  long positives = 0;
  for (std::uint8_t o : occupied) positives += o != 0;
  FS_THROW_UNLESS(positives > 0 && positives < n, source, ": the ", n,
                  " occupancy labels are all one class (", positives, " occupied)");

  // Features once, over the states the samples touch.
  SparseFeatures x;
  std::unordered_map<int, int> local;
  std::vector<int> states;
  {
    const auto f = std::make_unique<RbfFeatures<D>>();
    for (long i = 0; i < n; ++i) {
      grid.Evaluate(points.col(i), f.get());
      for (int k = 0; k < f->count; ++k) {
        const auto it = local.emplace(f->index[k], static_cast<int>(states.size())).first;
        if (it->second == static_cast<int>(states.size())) states.push_back(f->index[k]);
        x.column.push_back(it->second);
        x.value.push_back(f->phi[k]);
      }
      x.start.push_back(static_cast<int>(x.column.size()));
    }
  }
  const int m = static_cast<int>(states.size());
  FS_THROW_UNLESS(m > 0, source, ": no occupancy sample lies within the grid's cut-off radius");
  Eigen::VectorXd y(n);
  for (long i = 0; i < n; ++i) y[i] = occupied[static_cast<std::size_t>(i)] != 0 ? 1.0 : 0.0;

  // Newton (IRLS) on theta = (w, b); the bias is the last coordinate.
  Eigen::VectorXd w = Eigen::VectorXd::Zero(m);
  const double prior = static_cast<double>(positives) / n;
  double b = std::log(prior / (1 - prior));
  Eigen::VectorXd f(n), f_trial(n), grad(m + 1), w_trial(m);
  Eigen::MatrixXd hess(m + 1, m + 1);
  Latent(x, w, b, &f);
  double loss = Loss(f, y, w, l2);
  const double tolerance = 1e-8 * std::max(1.0, std::sqrt(static_cast<double>(n)));
  double grad_norm = 0;
  for (int iteration = 0; iteration <= kMaxNewtonIterations; ++iteration) {
    grad.head(m) = l2 * w;
    grad[m] = 0;
    hess.setZero();
    hess.diagonal().head(m).setConstant(l2);
    for (long i = 0; i < n; ++i) {
      const double p = Sigmoid(f[i]), r = p - y[i], s = p * (1 - p);
      const int begin = x.start[i], end = x.start[i + 1];
      for (int k = begin; k < end; ++k) {
        const int ck = x.column[k];
        const double sv = s * x.value[k];
        grad[ck] += r * x.value[k];
        hess(ck, m) += sv;
        for (int l = begin; l < end; ++l) hess(ck, x.column[l]) += sv * x.value[l];
      }
      grad[m] += r;
      hess(m, m) += s;
    }
    hess.row(m).head(m) = hess.col(m).head(m).transpose();
    grad_norm = grad.norm();
    if (grad_norm <= tolerance) {
      return OccupancyField<D>(
          grid,
          [&] {
            Eigen::VectorXd full = Eigen::VectorXd::Zero(grid.size());
            for (int k = 0; k < m; ++k) full[states[k]] = w[k];
            return full;
          }(),
          b, source);
    }
    if (iteration == kMaxNewtonIterations) break;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(hess);
    FS_THROW_UNLESS(ldlt.info() == Eigen::Success, source,
                    ": the Newton system of the occupancy fit is singular");
    const Eigen::VectorXd step = -ldlt.solve(grad);
    const double slope = grad.dot(step);
    FS_THROW_UNLESS(std::isfinite(slope) && slope < 0, source,
                    ": the Newton step of the occupancy fit is not a descent direction");
    // Backtracking (Armijo) line search.
    double t = 1;
    bool accepted = false;
    for (int ls = 0; ls < 50; ++ls, t *= 0.5) {
      w_trial = w + t * step.head(m);
      const double b_trial = b + t * step[m];
      Latent(x, w_trial, b_trial, &f_trial);
      const double trial = Loss(f_trial, y, w_trial, l2);
      if (trial <= loss + 1e-4 * t * slope) {
        w.swap(w_trial);
        b = b_trial;
        f.swap(f_trial);
        loss = trial;
        accepted = true;
        break;
      }
    }
    if (!accepted) break;  // no decrease possible in floating point: the gradient test decides
  }
  Fail(source, ": the occupancy fit did not converge in ", kMaxNewtonIterations,
       " Newton iterations (gradient norm ", grad_norm, ", tolerance ", tolerance, ")");
}

template <int D>
void SampleObstacleOccupancy(const std::function<double(const Vec<D>&)>& signed_distance,
                             const Vec<D>& lo, const Vec<D>& hi, double spacing,
                             Eigen::Matrix<double, D, Eigen::Dynamic>* points,
                             std::vector<std::uint8_t>* occupied) {
  FS_THROW_UNLESS(lo.allFinite() && hi.allFinite() && (hi.array() >= lo.array()).all(),
                  "obstacle samples: box [", lo.transpose(), "] to [", hi.transpose(),
                  "] is not a finite non-empty box");
  FS_THROW_UNLESS(std::isfinite(spacing) && spacing > 0, "obstacle samples: spacing ", spacing,
                  " must be positive and finite");
  long n[D], total = 1;
  for (int a = 0; a < D; ++a) {
    const double cells = std::floor((hi[a] - lo[a]) / spacing + 1e-9);
    FS_THROW_UNLESS(cells < kMaxSamples, "obstacle samples: more than ", kMaxSamples,
                    " samples (spacing ", spacing, ")");
    n[a] = static_cast<long>(cells) + 1;
    total *= n[a];
    FS_THROW_UNLESS(total <= kMaxSamples, "obstacle samples: more than ", kMaxSamples,
                    " samples (spacing ", spacing, ")");
  }
  points->resize(D, total);
  occupied->resize(static_cast<std::size_t>(total));
  for (long p = 0; p < total; ++p) {
    long rest = p;
    Vec<D> s;
    for (int a = 0; a < D; ++a) {
      s[a] = lo[a] + spacing * static_cast<double>(rest % n[a]);
      rest /= n[a];
    }
    points->col(p) = s;
    (*occupied)[static_cast<std::size_t>(p)] = signed_distance(s) <= 0 ? 1 : 0;
  }
}

template OccupancyField<2> FitOccupancyField<2>(const RbfGrid<2>&,
                                                const Eigen::Matrix<double, 2, -1>&,
                                                const std::vector<std::uint8_t>&, double,
                                                const std::string&);
template OccupancyField<3> FitOccupancyField<3>(const RbfGrid<3>&,
                                                const Eigen::Matrix<double, 3, -1>&,
                                                const std::vector<std::uint8_t>&, double,
                                                const std::string&);
template void SampleObstacleOccupancy<2>(const std::function<double(const Vec<2>&)>&, const Vec<2>&,
                                         const Vec<2>&, double, Eigen::Matrix<double, 2, -1>*,
                                         std::vector<std::uint8_t>*);
template void SampleObstacleOccupancy<3>(const std::function<double(const Vec<3>&)>&, const Vec<3>&,
                                         const Vec<3>&, double, Eigen::Matrix<double, 3, -1>*,
                                         std::vector<std::uint8_t>*);

}  // namespace foresight::imitation
