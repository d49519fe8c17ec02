/// The "diffeo_eflow" artifact (docs/artifact_schema.md, common header:
/// inference/engine/artifact.h):
///   /model      attrs dimension d, layers L, features F, speed
///   /model/goal [d] float64                 x_goal
///   /model/transformed [L] int64            b_l = l mod d (checked)
///   /weights/omega [L, F, d-1] float64      Omega_l
///   /weights/phase [L, F] float64           beta_l
///   /weights/scale [L, F] float64           sigma_l
///   /weights/translate [L, F] float64       tau_l
#include "inference/imitation/eflow.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/h5.h"
#include "inference/engine/artifact.h"

namespace foresight::imitation {

namespace {

constexpr int kMax = EFlowModel::kMaxDimension;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMax, 1>;
using SmallRow = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMax>;
using SmallMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMax, kMax>;

/// Index of the j-th fixed coordinate of a layer changing coordinate b.
inline int Fixed(int j, int b) { return j < b ? j : j + 1; }

/// s(x_a), t(x_a) and, when ds is not null, ds/dx and dt/dx as full [d] vectors (entry b is 0).
void LayerTerms(const EFlowCouplingLayer& layer, const SmallVec& x, double* s, double* t,
                SmallVec* ds, SmallVec* dt) {
  const int d = static_cast<int>(x.size()), b = layer.transformed;
  const int f = static_cast<int>(layer.phase.size());
  double sum_s = 0, sum_t = 0;
  if (ds) {
    ds->setZero(d);
    dt->setZero(d);
  }
  for (int k = 0; k < f; ++k) {
    double arg = layer.phase[k];
    for (int j = 0; j + 1 < d; ++j) arg += layer.omega(k, j) * x[Fixed(j, b)];
    const double c = std::cos(arg);
    sum_s += layer.scale[k] * c;
    sum_t += layer.translate[k] * c;
    if (ds) {
      const double sn = std::sin(arg);
      const double gs = layer.scale[k] * sn, gt = layer.translate[k] * sn;
      for (int j = 0; j + 1 < d; ++j) {
        (*ds)[Fixed(j, b)] -= gs * layer.omega(k, j);
        (*dt)[Fixed(j, b)] -= gt * layer.omega(k, j);
      }
    }
  }
  const double norm = std::sqrt(2.0 / f);
  *s = norm * sum_s;
  *t = norm * sum_t;
  if (ds) {
    *ds *= norm;
    *dt *= norm;
  }
}

/// psi(x) into *z and, when jacobian is not null, J into *jacobian.
void Propagate(const std::vector<EFlowCouplingLayer>& layers, const SmallVec& x, SmallVec* z,
               SmallMat* jacobian) {
  const int d = static_cast<int>(x.size());
  *z = x;
  if (jacobian) jacobian->setIdentity(d, d);
  SmallVec ds, dt;
  for (const EFlowCouplingLayer& layer : layers) {
    const int b = layer.transformed;
    double s, t;
    LayerTerms(layer, *z, &s, &t, jacobian ? &ds : nullptr, jacobian ? &dt : nullptr);
    const double es = std::exp(s), xb = (*z)[b];
    if (jacobian) {
      // Row b of the layer Jacobian; the other rows are the identity.
      SmallRow row = (xb * es * ds + dt).transpose();
      row[b] = es;
      const SmallRow new_row = row * (*jacobian);
      jacobian->row(b) = new_row;
    }
    (*z)[b] = xb * es + t;
  }
}

std::string LayerName(const std::string& source, int l) {
  return source + ": layer " + std::to_string(l);
}

/// A dataset of exactly `shape` (row-major) with finite values; an Error naming the field
/// otherwise.
std::vector<double> ReadShaped(const h5::File& f, const std::string& name,
                               const std::vector<std::size_t>& shape) {
  h5::Array<double> a = f.ReadDouble(name);
  if (a.shape != shape) {
    std::string got, want;
    for (std::size_t n : a.shape) got += (got.empty() ? "" : " x ") + std::to_string(n);
    for (std::size_t n : shape) want += (want.empty() ? "" : " x ") + std::to_string(n);
    Fail(f.path(), ": ", name, " has shape [", got, "], expected [", want, "]");
  }
  for (std::size_t i = 0; i < a.data.size(); ++i)
    FS_THROW_UNLESS(std::isfinite(a.data[i]), f.path(), ": ", name, " holds a non-finite value (",
                    a.data[i], ") at flat index ", i);
  return std::move(a.data);
}

}  // namespace

EFlowModel::EFlowModel(int dimension, std::vector<EFlowCouplingLayer> layers, Eigen::VectorXd goal,
                       double speed, const std::string& source)
    : dimension_(dimension),
      layers_(std::move(layers)),
      goal_(std::move(goal)),
      speed_(speed),
      source_(source) {
  FS_THROW_UNLESS(dimension >= 2 && dimension <= kMaxDimension, source, ": dimension ", dimension,
                  " is outside [2, ", kMaxDimension, "]");
  FS_THROW_UNLESS(!layers_.empty(), source, ": no coupling layers");
  FS_THROW_UNLESS(goal_.size() == dimension, source, ": goal has ", goal_.size(),
                  " entries, expected ", dimension);
  FS_THROW_UNLESS(goal_.allFinite(), source, ": goal holds a non-finite value");
  FS_THROW_UNLESS(std::isfinite(speed) && speed > 0, source, ": speed must be > 0, got ", speed);
  const long f = layers_[0].phase.size();
  FS_THROW_UNLESS(f >= 1, source, ": layer 0 has no features");
  for (int l = 0; l < num_layers(); ++l) {
    const EFlowCouplingLayer& layer = layers_[l];
    const std::string where = LayerName(source, l);
    FS_THROW_UNLESS(layer.transformed == l % dimension, where, " changes coordinate ",
                    layer.transformed, ", expected ", l % dimension, " (l mod d)");
    FS_THROW_UNLESS(layer.omega.rows() == f && layer.omega.cols() == dimension - 1, where,
                    ": omega is ", layer.omega.rows(), " x ", layer.omega.cols(), ", expected ", f,
                    " x ", dimension - 1);
    FS_THROW_UNLESS(layer.phase.size() == f, where, ": phase has ", layer.phase.size(),
                    " entries, expected ", f);
    FS_THROW_UNLESS(layer.scale.size() == f, where, ": scale has ", layer.scale.size(),
                    " entries, expected ", f);
    FS_THROW_UNLESS(layer.translate.size() == f, where, ": translate has ", layer.translate.size(),
                    " entries, expected ", f);
    FS_THROW_UNLESS(layer.omega.allFinite() && layer.phase.allFinite() && layer.scale.allFinite() &&
                        layer.translate.allFinite(),
                    where, ": a non-finite weight");
  }
  goal_image_ = Forward(goal_);
  FS_THROW_UNLESS(goal_image_.allFinite(), source, ": psi(goal) is not finite");
}

void EFlowModel::CheckAnswer(bool finite, const Eigen::VectorXd& x, const char* what) const {
  if (finite || !x.allFinite()) return;
  Fail(source_, ": ", what, " overflows at the state (", x.transpose(),
       "): the coupling layers' weights are too large for it");
}

Eigen::VectorXd EFlowModel::Forward(const Eigen::VectorXd& x, Eigen::MatrixXd* J) const {
  FS_THROW_UNLESS(x.size() == dimension_, "EFlowModel::Forward: x has ", x.size(),
                  " entries, expected ", dimension_);
  SmallVec z;
  if (J) {
    SmallMat jac;
    Propagate(layers_, x, &z, &jac);
    *J = jac;
    CheckAnswer(z.allFinite() && jac.allFinite(), x, "psi(x) or its Jacobian");
  } else {
    Propagate(layers_, x, &z, nullptr);
    CheckAnswer(z.allFinite(), x, "psi(x)");
  }
  return z;
}

Eigen::VectorXd EFlowModel::Inverse(const Eigen::VectorXd& z) const {
  FS_THROW_UNLESS(z.size() == dimension_, "EFlowModel::Inverse: z has ", z.size(),
                  " entries, expected ", dimension_);
  SmallVec x = z;
  for (auto it = layers_.rbegin(); it != layers_.rend(); ++it) {
    double s, t;
    LayerTerms(*it, x, &s, &t, nullptr, nullptr);  // depends on the fixed coordinates only
    x[it->transformed] = (x[it->transformed] - t) * std::exp(-s);
  }
  CheckAnswer(x.allFinite(), z, "psi^-1(z)");
  return x;
}

Eigen::VectorXd EFlowModel::Velocity(const Eigen::VectorXd& x) const {
  FS_THROW_UNLESS(x.size() == dimension_, "EFlowModel::Velocity: x has ", x.size(),
                  " entries, expected ", dimension_);
  SmallVec z;
  SmallMat jac;
  Propagate(layers_, x, &z, &jac);
  const SmallVec diff = z - goal_image_;
  const double norm = diff.norm();
  CheckAnswer(std::isfinite(norm) && jac.allFinite(), x, "psi(x) or its Jacobian");
  if (norm == 0) return Eigen::VectorXd::Zero(dimension_);
  // det J = prod_l exp(s_l) > 0: J is always invertible.
  const Eigen::PartialPivLU<SmallMat> lu(jac);
  const SmallVec v = (-speed_ / norm) * lu.solve(diff);
  CheckAnswer(v.allFinite(), x, "the velocity");
  return v;
}

Eigen::VectorXd EFlowModel::VelocityWithRepulsor(const Eigen::VectorXd& x,
                                                 const Eigen::VectorXd& grad_p, double beta) const {
  FS_THROW_UNLESS(grad_p.size() == dimension_, "EFlowModel::VelocityWithRepulsor: grad_p has ",
                  grad_p.size(), " entries, expected ", dimension_);
  FS_THROW_UNLESS(grad_p.allFinite(), "EFlowModel::VelocityWithRepulsor: grad_p is not finite");
  FS_THROW_UNLESS(std::isfinite(beta) && beta >= 0,
                  "EFlowModel::VelocityWithRepulsor: beta must be finite and >= 0, got ", beta);
  return Velocity(x) - beta * grad_p;
}

void EFlowModel::Save(const std::string& path, const std::string& config_yaml,
                      std::int64_t seed) const {
  const std::size_t l = layers_.size(), f = num_features(), d = dimension_;
  std::vector<double> omega(l * f * (d - 1)), phase(l * f), scale(l * f), translate(l * f);
  std::vector<std::int64_t> transformed(l);
  for (std::size_t i = 0; i < l; ++i) {
    const EFlowCouplingLayer& layer = layers_[i];
    transformed[i] = layer.transformed;
    for (std::size_t k = 0; k < f; ++k) {
      phase[i * f + k] = layer.phase[k];
      scale[i * f + k] = layer.scale[k];
      translate[i * f + k] = layer.translate[k];
      for (std::size_t j = 0; j + 1 < d; ++j)
        omega[(i * f + k) * (d - 1) + j] = layer.omega(static_cast<long>(k), static_cast<long>(j));
    }
  }
  h5::WriteAtomically(path, [&](h5::File* file) {
    Artifact::WriteHeader(file, kEFlowModelType, config_yaml, seed);
    file->SetAttr("/model", "dimension", static_cast<std::int64_t>(d));
    file->SetAttr("/model", "layers", static_cast<std::int64_t>(l));
    file->SetAttr("/model", "features", static_cast<std::int64_t>(f));
    file->SetAttr("/model", "speed", speed_);
    file->Write("/model/goal", goal_.data(), {d});
    file->Write("/model/transformed", transformed.data(), {l});
    file->Write("/weights/omega", omega.data(), {l, f, d - 1});
    file->Write("/weights/phase", phase.data(), {l, f});
    file->Write("/weights/scale", scale.data(), {l, f});
    file->Write("/weights/translate", translate.data(), {l, f});
  });
}

EFlowModel EFlowModel::Load(const std::string& path) {
  Artifact a = Artifact::Open(path, kEFlowModelType);
  const h5::File& f = a.file();
  try {
    const int d = a.IntAttr("/model", "dimension", 2, kMaxDimension);
    const int l = a.IntAttr("/model", "layers", 1, 1 << 16);
    const int nf = a.IntAttr("/model", "features", 1, 1 << 20);
    const double speed = a.DoubleAttr("/model", "speed", std::numeric_limits<double>::min(), 1e300);
    const std::size_t ud = d, ul = l, uf = nf;
    const std::vector<double> goal = ReadShaped(f, "/model/goal", {ud});
    const h5::Array<std::int64_t> transformed = f.ReadInt("/model/transformed");
    FS_THROW_UNLESS(transformed.shape == std::vector<std::size_t>{ul}, path,
                    ": /model/transformed must have ", l, " entries");
    const std::vector<double> omega = ReadShaped(f, "/weights/omega", {ul, uf, ud - 1});
    const std::vector<double> phase = ReadShaped(f, "/weights/phase", {ul, uf});
    const std::vector<double> scale = ReadShaped(f, "/weights/scale", {ul, uf});
    const std::vector<double> translate = ReadShaped(f, "/weights/translate", {ul, uf});
    std::vector<EFlowCouplingLayer> layers(ul);
    for (std::size_t i = 0; i < ul; ++i) {
      EFlowCouplingLayer& layer = layers[i];
      FS_THROW_UNLESS(transformed.data[i] == static_cast<std::int64_t>(i % ud), path,
                      ": /model/transformed[", i, "] is ", transformed.data[i], ", expected ",
                      i % ud, " (l mod d)");
      layer.transformed = static_cast<int>(transformed.data[i]);
      layer.omega.resize(nf, d - 1);
      layer.phase.resize(nf);
      layer.scale.resize(nf);
      layer.translate.resize(nf);
      for (std::size_t k = 0; k < uf; ++k) {
        layer.phase[k] = phase[i * uf + k];
        layer.scale[k] = scale[i * uf + k];
        layer.translate[k] = translate[i * uf + k];
        for (std::size_t j = 0; j + 1 < ud; ++j)
          layer.omega(static_cast<long>(k), static_cast<long>(j)) =
              omega[(i * uf + k) * (ud - 1) + j];
      }
    }
    return EFlowModel(d, std::move(layers), Eigen::Map<const Eigen::VectorXd>(goal.data(), d),
                      speed, path);
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(path, 0) == 0) throw;
    Fail(path, ": ", what);
  }
}

}  // namespace foresight::imitation
