#include "inference/mapping/hinge_map.h"

#include <cmath>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::occupancy {
namespace {

constexpr double kPiOver8 = M_PI / 8.0;

double Sigmoid(double a) { return 1.0 / (1.0 + std::exp(-a)); }

void WriteVector(h5::File* f, const std::string& name, const Eigen::VectorXd& v,
                 StoredPrecision p) {
  const std::vector<std::size_t> shape{static_cast<std::size_t>(v.size())};
  if (p == StoredPrecision::kFloat64) {
    f->Write(name, v.data(), shape);
  } else {
    const Eigen::VectorXf vf = v.cast<float>();
    f->Write(name, vf.data(), shape);
  }
}

Eigen::VectorXd ReadVector(const h5::File& f, const std::string& name, long size) {
  Eigen::MatrixXd m = f.ReadMatrixD(name, size, 1);
  return m.col(0);
}

}  // namespace

const char* ModelType(HingeMapKind kind) {
  switch (kind) {
    case HingeMapKind::kHilbert:
      return kHilbertMapType;
    case HingeMapKind::kFastBhm:
      return kFastBhmType;
    case HingeMapKind::kBhm:
      return kBhmType;
  }
  return "?";
}

double PredictiveProbability(double latent_mean, double latent_variance) {
  return Sigmoid(latent_mean / std::sqrt(1.0 + kPiOver8 * latent_variance));
}

HingeMap::HingeMap(HingeMapKind kind, HingeGrid grid, HingeWeights weights, double prior_mean,
                   double prior_variance)
    : kind_(kind),
      grid_(std::move(grid)),
      weights_(std::move(weights)),
      prior_mean_(prior_mean),
      prior_variance_(prior_variance) {
  const long t = grid_.size();
  FS_THROW_UNLESS(weights_.mean.size() == t, ModelType(kind_), ": ", weights_.mean.size(),
                  " weight means for a grid of ", t, " features");
  FS_THROW_UNLESS(weights_.mean.allFinite(), ModelType(kind_), ": weight means are not finite");
  if (kind_ == HingeMapKind::kHilbert) {
    weights_.variance.resize(0);
    weights_.covariance.resize(0, 0);
    return;
  }
  if (kind_ == HingeMapKind::kBhm) {
    FS_THROW_UNLESS(weights_.covariance.rows() == t && weights_.covariance.cols() == t,
                    ModelType(kind_), ": covariance is ", weights_.covariance.rows(), " x ",
                    weights_.covariance.cols(), ", expected ", t, " x ", t);
    // Only the diagonal is checked below; a NaN off-diagonal entry made every query NaN.
    for (Eigen::Index j = 0; j < t; ++j)
      for (Eigen::Index i = 0; i < t; ++i)
        FS_THROW_UNLESS(std::isfinite(weights_.covariance(i, j)), ModelType(kind_),
                        ": covariance entry (", i, ", ", j, ") is ", weights_.covariance(i, j),
                        "; expected finite values");
    weights_.variance = weights_.covariance.diagonal();
  } else {
    weights_.covariance.resize(0, 0);
  }
  FS_THROW_UNLESS(weights_.variance.size() == t, ModelType(kind_), ": ", weights_.variance.size(),
                  " weight variances for a grid of ", t, " features");
  FS_THROW_UNLESS((weights_.variance.array() > 0).all() && weights_.variance.allFinite(),
                  ModelType(kind_), ": weight variances must be positive and finite");
  FS_THROW_UNLESS(
      std::isfinite(prior_mean_) && prior_variance_ > 0 && std::isfinite(prior_variance_),
      ModelType(kind_), ": prior N(", prior_mean_, ", ", prior_variance_, ") is invalid");
}

MapWorkspace HingeMap::MakeWorkspace() const {
  MapWorkspace ws;
  const auto k = static_cast<std::size_t>(grid_.max_active());
  ws.index.resize(k);
  ws.phi.resize(k);
  ws.dphi_dx.resize(k);
  ws.dphi_dy.resize(k);
  ws.scratch.resize(k);
  return ws;
}

bool HingeMap::Latent(double x, double y, MapWorkspace* ws, double* mean, double* variance) const {
  const int k = grid_.Features(x, y, ws->index.data(), ws->phi.data());
  const int* idx = ws->index.data();
  const double* phi = ws->phi.data();
  if (k == 0) {
    *mean = prior_mean_;
    *variance = kind_ == HingeMapKind::kHilbert ? 0.0 : prior_variance_;
    return false;
  }
  double m = 0, v = 0;
  const double* mu = weights_.mean.data();
  for (int i = 0; i < k; ++i) m += phi[i] * mu[idx[i]];
  if (kind_ == HingeMapKind::kFastBhm) {
    const double* s2 = weights_.variance.data();
    for (int i = 0; i < k; ++i) v += phi[i] * phi[i] * s2[idx[i]];
  } else if (kind_ == HingeMapKind::kBhm) {
    for (int i = 0; i < k; ++i) {
      double row = 0;
      for (int j = 0; j < k; ++j) row += weights_.covariance(idx[i], idx[j]) * phi[j];
      v += phi[i] * row;
    }
  }
  *mean = m;
  *variance = v;
  return true;
}

double HingeMap::Probability(double x, double y, MapWorkspace* ws) const {
  double m, v;
  // No features: the prior probability, as Query() answers (not the probit of the prior).
  if (!Latent(x, y, ws, &m, &v)) return Sigmoid(prior_mean_);
  if (kind_ == HingeMapKind::kHilbert) return Sigmoid(m);
  return PredictiveProbability(m, v);
}

// p = sigmoid(m kappa), kappa = (1 + pi v / 8)^-1/2:
//   dp = p (1 - p) (kappa dm + m dkappa),  dkappa = -(pi / 16) (1 + pi v / 8)^-3/2 dv,
//   dm = sum_t mu_t dphi_t,  dv = 2 sum_t s2_t phi_t dphi_t (Fast-BHM), 2 dphi' Sigma phi (BHM).
QueryResult HingeMap::Query(double x, double y, MapWorkspace* ws) const {
  QueryResult q;
  int* idx = ws->index.data();
  double* phi = ws->phi.data();
  double* gx = ws->dphi_dx.data();
  double* gy = ws->dphi_dy.data();
  const int k = grid_.FeaturesWithGradient(x, y, idx, phi, gx, gy);
  if (k == 0) {
    q.probability = Sigmoid(prior_mean_);
    q.variance = kind_ == HingeMapKind::kHilbert ? 0.0 : prior_variance_;
    return q;
  }
  const double* mu = weights_.mean.data();
  double m = 0, mx = 0, my = 0, v = 0, vx = 0, vy = 0;
  for (int i = 0; i < k; ++i) {
    const double w = mu[idx[i]];
    m += phi[i] * w;
    mx += gx[i] * w;
    my += gy[i] * w;
  }
  if (kind_ == HingeMapKind::kFastBhm) {
    const double* s2 = weights_.variance.data();
    for (int i = 0; i < k; ++i) {
      const double a = s2[idx[i]] * phi[i];
      v += a * phi[i];
      vx += a * gx[i];
      vy += a * gy[i];
    }
    vx *= 2;
    vy *= 2;
  } else if (kind_ == HingeMapKind::kBhm) {
    for (int i = 0; i < k; ++i) {
      double row = 0;
      for (int j = 0; j < k; ++j) row += weights_.covariance(idx[i], idx[j]) * phi[j];
      v += phi[i] * row;
      vx += 2 * gx[i] * row;
      vy += 2 * gy[i] * row;
    }
  }
  if (kind_ == HingeMapKind::kHilbert) {
    const double p = Sigmoid(m);
    q.probability = p;
    q.dp_dx = p * (1 - p) * mx;
    q.dp_dy = p * (1 - p) * my;
    return q;
  }
  const double s = 1.0 + kPiOver8 * v;
  const double kappa = 1.0 / std::sqrt(s);
  const double dkappa = -0.5 * kPiOver8 * kappa / s;  // d kappa / d v
  const double p = Sigmoid(m * kappa);
  const double dp = p * (1 - p);
  q.probability = p;
  q.dp_dx = dp * (kappa * mx + m * dkappa * vx);
  q.dp_dy = dp * (kappa * my + m * dkappa * vy);
  q.variance = v;
  return q;
}

Eigen::Vector4d HingeMap::Extent() const {
  const auto& c = grid_.config();
  const double r = c.cutoff_radius;
  return {c.x_min - r, c.x_min + (grid_.nx() - 1) * c.spacing + r, c.y_min - r,
          c.y_min + (grid_.ny() - 1) * c.spacing + r};
}

// ---- artifact ------------------------------------------------------------------------------

void HingeMap::Save(const std::string& path, const std::string& config_yaml, std::int64_t seed,
                    StoredPrecision precision) const {
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, model_type(), config_yaml, seed);
    const auto& c = grid_.config();
    f->SetAttr("/model", "x_min", c.x_min);
    f->SetAttr("/model", "x_max", c.x_max);
    f->SetAttr("/model", "y_min", c.y_min);
    f->SetAttr("/model", "y_max", c.y_max);
    f->SetAttr("/model", "spacing", c.spacing);
    f->SetAttr("/model", "gamma", c.gamma);
    f->SetAttr("/model", "cutoff_radius", c.cutoff_radius);
    f->SetAttr("/model", "prior_mean", prior_mean_);
    f->SetAttr("/model", "prior_variance", prior_variance_);
    WriteVector(f, "/weights/mean", weights_.mean, precision);
    if (kind_ == HingeMapKind::kFastBhm)
      WriteVector(f, "/weights/variance", weights_.variance, precision);
    if (kind_ == HingeMapKind::kBhm) {
      if (precision == StoredPrecision::kFloat64) {
        f->WriteMatrix("/weights/covariance", weights_.covariance);
      } else {
        f->WriteMatrix("/weights/covariance", weights_.covariance.cast<float>());
      }
    }
  });
}

HingeMap HingeMap::Load(const std::string& path, const std::string& expected_type) {
  Artifact a = Artifact::Open(path, expected_type);
  const std::string& type = a.model_type();
  HingeMapKind kind;
  if (type == kHilbertMapType) {
    kind = HingeMapKind::kHilbert;
  } else if (type == kFastBhmType) {
    kind = HingeMapKind::kFastBhm;
  } else if (type == kBhmType) {
    kind = HingeMapKind::kBhm;
  } else {
    Fail(path, ": artifact holds a '", type, "' model, not a hinge-feature occupancy map");
  }
  const h5::File& f = a.file();
  HingeGridConfig c;
  c.x_min = a.DoubleAttr("/model", "x_min", -1e9, 1e9);
  c.x_max = a.DoubleAttr("/model", "x_max", -1e9, 1e9);
  c.y_min = a.DoubleAttr("/model", "y_min", -1e9, 1e9);
  c.y_max = a.DoubleAttr("/model", "y_max", -1e9, 1e9);
  c.spacing = a.DoubleAttr("/model", "spacing", 1e-12, 1e12);
  c.gamma = a.DoubleAttr("/model", "gamma", 1e-12, 1e12);
  c.cutoff_radius = a.DoubleAttr("/model", "cutoff_radius", 1e-12, 1e12);
  try {
    HingeGrid grid(c);
    const long t = grid.size();
    HingeWeights w;
    w.mean = ReadVector(f, "/weights/mean", t);
    if (kind == HingeMapKind::kFastBhm) w.variance = ReadVector(f, "/weights/variance", t);
    if (kind == HingeMapKind::kBhm) w.covariance = f.ReadMatrixD("/weights/covariance", t, t);
    return HingeMap(kind, std::move(grid), std::move(w),
                    a.DoubleAttr("/model", "prior_mean", -1e12, 1e12),
                    a.DoubleAttr("/model", "prior_variance", 1e-300, 1e300));
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(path, 0) == 0) throw;
    Fail(path, ": ", what);
  }
}

}  // namespace foresight::occupancy
