#include "inference/otnet/otnet_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::otnet {
namespace {

constexpr double kLogTwoPi = 1.8378770664093454836;
// Alpha must sum to one up to this (a hand-made mixture off by more is a caller's error).
constexpr double kAlphaSumTolerance = 1e-6;

// k_j(0) = exp(-gamma c_j^2): the same expression as TimeBasis::Evaluate at t = 0, so the first row
// of a design at tau = 0 equals it bit for bit.
double BasisAtStart(const TimeBasis& b, int j) {
  const double d = 0.0 - b.centres()[j];
  return std::exp(-b.gamma() * d * d);
}

// Var = s^2 (Normal) or 2 s^2 (Laplace) per weight.
double VarianceFactor(MixtureFamily f) { return f == MixtureFamily::kLaplace ? 2.0 : 1.0; }

MixtureFamily ParseFamily(const std::string& name, const std::string& where) {
  if (name == "normal") return MixtureFamily::kNormal;
  if (name == "laplace") return MixtureFamily::kLaplace;
  Fail(where, " is '", name, "'; expected 'normal' or 'laplace'");
}

std::vector<std::string> LayerNames(int count) {
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) names.push_back("layer" + std::to_string(i));
  return names;
}

// Start-point statistics of one coordinate (d = 0: x, 1: y) of component q of an unconditioned
// mixture: c = k0' Var k0 (the variance of z(0)) and m0 = k0' mu (its mean).
struct StartMoments {
  double variance = 0, mean = 0;
};
StartMoments StartOf(const TimeBasis& b, const Mixture& m, int q, int d) {
  const int size = b.size();
  const double factor = VarianceFactor(m.family);
  StartMoments out;
  for (int j = 0; j < size; ++j) {
    const double k0 = BasisAtStart(b, j);
    const double s = m.scale(q, d * size + j);
    out.variance += k0 * k0 * factor * s * s;
    out.mean += k0 * m.mean(q, d * size + j);
  }
  return out;
}

// Checks a mixture's shapes and values against the model: Q components, 2M weights, alpha a
// distribution, finite means, positive finite scales (and gains when conditioned). No allocation.
void CheckMixture(const Mixture& m, int components, int weights, const char* where) {
  FS_THROW_UNLESS(m.alpha.size() == components && m.mean.rows() == components &&
                      m.mean.cols() == weights && m.scale.rows() == components &&
                      m.scale.cols() == weights,
                  where, ": mixture has ", m.alpha.size(), " weights, means ", m.mean.rows(), "x",
                  m.mean.cols(), ", scales ", m.scale.rows(), "x", m.scale.cols(),
                  "; the model has ", components, " components of ", weights, " weights");
  FS_THROW_UNLESS(m.alpha.allFinite() && m.alpha.minCoeff() >= 0 &&
                      std::abs(m.alpha.sum() - 1.0) <= kAlphaSumTolerance,
                  where, ": mixture weights must be non-negative and sum to 1 (sum ", m.alpha.sum(),
                  ", min ", m.alpha.minCoeff(), ")");
  FS_THROW_UNLESS(m.mean.allFinite(), where, ": mixture means are not finite");
  FS_THROW_UNLESS(m.scale.allFinite() && m.scale.minCoeff() > 0, where,
                  ": mixture scales must be positive and finite (min ", m.scale.minCoeff(), ")");
  if (m.conditioned) {
    FS_THROW_UNLESS(m.gain.rows() == components && m.gain.cols() == weights && m.gain.allFinite(),
                    where, ": conditioned mixture has gains of shape ", m.gain.rows(), "x",
                    m.gain.cols(), " (finite ", components, "x", weights, " expected)");
    FS_THROW_UNLESS(m.start.allFinite(), where, ": conditioned mixture has a non-finite start");
  }
}

void CheckTaus(const Eigen::VectorXd& taus, const char* where) {
  FS_THROW_UNLESS(taus.size() >= 1 && taus.allFinite(), where,
                  ": taus must be finite and non-empty (", taus.size(), " given)");
}

// Per-weight variances of coordinate d of component q into v [M] and, when conditioned, the
// weight-space vector Var k0 into vk0 [M] and c = k0' Var k0 (the rank-one term is
// (Var k0)(Var k0)' / c).
void WeightMoments(const TimeBasis& b, const Mixture& m, int q, int d, Eigen::VectorXd* v,
                   Eigen::VectorXd* vk0, double* c) {
  const int size = b.size();
  const double factor = VarianceFactor(m.family);
  v->resize(size);
  vk0->resize(size);
  *c = 0;
  for (int j = 0; j < size; ++j) {
    const double s = m.scale(q, d * size + j);
    (*v)[j] = factor * s * s;
    const double k0 = BasisAtStart(b, j);
    (*vk0)[j] = (*v)[j] * k0;
    *c += k0 * (*vk0)[j];
  }
}

}  // namespace

const char* ToString(MixtureFamily f) {
  return f == MixtureFamily::kLaplace ? "laplace" : "normal";
}

Eigen::VectorXd Mixture::Variance(int q) const {
  FS_THROW_UNLESS(q >= 0 && q < components(), "Mixture::Variance: component ", q,
                  " out of range [0, ", components(), ")");
  return VarianceFactor(family) * scale.row(q).transpose().array().square();
}

bool TrajectoryCollides(const BinaryGrid& map, const Eigen::Ref<const Eigen::MatrixX2d>& points,
                        double check_step) {
  FS_THROW_UNLESS(std::isfinite(check_step) && check_step > 0, "TrajectoryCollides: check_step ",
                  check_step, " must be positive and finite");
  FS_THROW_UNLESS(points.rows() >= 1, "TrajectoryCollides: empty polyline");
  // Waypoints first: a non-finite or outside waypoint collides, and with every waypoint inside the
  // grid each segment is shorter than its diagonal, which bounds the loop below.
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    if (map.OccupiedAt(points(i, 0), points(i, 1))) return true;
  for (Eigen::Index i = 0; i + 1 < points.rows(); ++i) {
    const double dx = points(i + 1, 0) - points(i, 0), dy = points(i + 1, 1) - points(i, 1);
    const double length = std::hypot(dx, dy);
    const long pieces = static_cast<long>(std::ceil(length / check_step));
    // Interior points at spacing length / pieces <= check_step; the endpoints were checked above.
    for (long s = 1; s < pieces; ++s) {
      const double t = static_cast<double>(s) / static_cast<double>(pieces);
      if (map.OccupiedAt(points(i, 0) + t * dx, points(i, 1) + t * dy)) return true;
    }
  }
  return false;
}

OtnetModel::OtnetModel(MapEncoder encoder, TrajectoryBasis basis, Mlp mlp, MixtureFamily family,
                       int components)
    : encoder_(std::move(encoder)),
      basis_(std::move(basis)),
      mlp_(std::move(mlp)),
      family_(family) {
  FS_THROW_UNLESS(encoder_.size() >= 1, "OtnetModel: the map encoder has an empty database");
  FS_THROW_UNLESS(basis_.size() >= 2, "OtnetModel: the trajectory basis has ", basis_.size(),
                  " functions (>= 2 expected)");
  FS_THROW_UNLESS(components >= 1, "OtnetModel: components ", components, " must be >= 1");
  FS_THROW_UNLESS(!mlp_.layers().empty(), "OtnetModel: the MLP has no layers");
  head_.components = components;
  head_.weights = basis_.weights();
  FS_THROW_UNLESS(mlp_.input_size() == encoder_.size(), "OtnetModel: the MLP takes ",
                  mlp_.input_size(), " inputs but the map database has ", encoder_.size(), " maps");
  FS_THROW_UNLESS(mlp_.output_size() == head_.Total(), "OtnetModel: the MLP gives ",
                  mlp_.output_size(), " outputs; the head of ", components, " components over ",
                  head_.weights, " weights needs ", head_.Total());
  log_scale_offset_ = Eigen::VectorXd::Zero(head_.weights);
}

void OtnetModel::SetLogScaleOffset(const Eigen::VectorXd& offset) {
  FS_THROW_UNLESS(offset.size() == head_.weights, "OtnetModel::SetLogScaleOffset: ", offset.size(),
                  " entries, expected ", head_.weights, " (2M)");
  FS_THROW_UNLESS(offset.allFinite(), "OtnetModel::SetLogScaleOffset: a value is not finite");
  log_scale_offset_ = offset;
}

OtnetModel OtnetModel::Load(const std::string& path) {
  Artifact a = Artifact::Open(path, kOtnetModelType);
  const h5::File& f = a.file();
  constexpr double kTiny = std::numeric_limits<double>::min();
  constexpr double kHuge = std::numeric_limits<double>::max();
  const int components = a.IntAttr("/model", "components", 1, 1 << 16);
  const MixtureFamily family =
      ParseFamily(f.GetStringAttr("/model", "family"), path + ": attribute /model/family");
  const int num_basis = a.IntAttr("/model", "num_basis", 2, 1 << 16);
  const double gamma = a.DoubleAttr("/model", "gamma", kTiny, kHuge);
  const double ridge = a.DoubleAttr("/model", "ridge", 0.0, kHuge);
  const double length_scale = a.DoubleAttr("/model", "length_scale", kTiny, kHuge);
  const int width = a.IntAttr("/model", "width", 1, 1 << 16);
  const int height = a.IntAttr("/model", "height", 1, 1 << 16);
  const int database_size = a.IntAttr("/model", "database_size", 1, 1 << 20);

  // Read as int64 (any integer type converts exactly), so a stored -1 or 256 is seen, not clipped.
  const h5::Array<std::int64_t> db = f.ReadInt("/model/database");
  const std::vector<std::size_t> expected = {static_cast<std::size_t>(database_size),
                                             static_cast<std::size_t>(height),
                                             static_cast<std::size_t>(width)};
  if (db.shape != expected) {
    std::string shape;
    for (std::size_t i = 0; i < db.shape.size(); ++i)
      shape += (i ? "x" : "") + std::to_string(db.shape[i]);
    Fail(path, ": dataset /model/database has shape [", shape, "], expected [", database_size, "x",
         height, "x", width, "] (attributes database_size x height x width)");
  }
  std::vector<BinaryGrid> database(static_cast<std::size_t>(database_size),
                                   BinaryGrid(width, height));
  const std::size_t cells = static_cast<std::size_t>(width) * height;
  for (std::size_t i = 0; i < db.Size(); ++i) {
    const std::int64_t v = db.data[i];
    FS_THROW_UNLESS(v == 0 || v == 1, path, ": dataset /model/database holds ", v, " at map ",
                    i / cells, ", row ", (i % cells) / width, ", column ", i % width,
                    " (0 or 1 expected)");
    database[i / cells].cells[i % cells] = static_cast<std::uint8_t>(v);
  }

  FS_THROW_UNLESS(f.Exists("/weights"), path, ": missing group /weights");
  const std::vector<std::string> members = f.List("/weights");
  const std::vector<std::string> names = LayerNames(static_cast<int>(members.size()));
  const std::set<std::string> wanted(names.begin(), names.end());
  for (const std::string& m : members)
    FS_THROW_UNLESS(wanted.count(m) == 1, path, ": unexpected member /weights/", m, " (",
                    names.size(), " members expected to be named layer0 to layer", names.size() - 1,
                    ")");
  FS_THROW_UNLESS(!names.empty(), path, ": group /weights holds no layers");
  Mlp mlp = Mlp::Load(f, "/weights/", names);
  for (std::size_t i = 0; i < mlp.layers().size(); ++i)
    FS_THROW_UNLESS(mlp.layers()[i].weight.allFinite() && mlp.layers()[i].bias.allFinite(), path,
                    ": /weights/", names[i], " is not finite");
  FS_THROW_UNLESS(mlp.input_size() == database_size, path, ": /weights/layer0/weight takes ",
                  mlp.input_size(), " inputs; attribute /model/database_size is ", database_size);
  const OtnetHead head{components, 2 * num_basis};
  FS_THROW_UNLESS(mlp.output_size() == head.Total(), path, ": /weights/", names.back(),
                  "/weight gives ", mlp.output_size(), " outputs; attributes /model/components ",
                  components, " and /model/num_basis ", num_basis, " need ", head.Total(),
                  " = components (1 + 4 num_basis)");
  try {
    OtnetModel model(MapEncoder(std::move(database), length_scale),
                     TrajectoryBasis(num_basis, gamma, ridge), std::move(mlp), family, components);
    if (f.Exists("/model/log_scale_offset")) {
      const h5::Array<double> o = f.ReadDouble("/model/log_scale_offset");
      FS_THROW_UNLESS(o.shape.size() == 1 && o.Size() == static_cast<std::size_t>(2 * num_basis),
                      path, ": dataset /model/log_scale_offset has ", o.Size(),
                      " values, expected ", 2 * num_basis, " (2 num_basis)");
      // exp(clamp(z - o) + o) must stay finite (and its square, the variance): |o| <= 100.
      for (std::size_t i = 0; i < o.Size(); ++i)
        FS_THROW_UNLESS(std::abs(o.data[i]) <= 100, path, ": /model/log_scale_offset[", i, "] is ",
                        o.data[i], "; expected a log scale from -100 to 100");
      model.SetLogScaleOffset(
          Eigen::Map<const Eigen::VectorXd>(o.data.data(), static_cast<Eigen::Index>(o.Size())));
    }
    return model;
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(path, 0) == 0) throw;
    Fail(path, ": ", what);
  }
}

void OtnetModel::Save(const std::string& path, const std::string& config_yaml,
                      std::int64_t seed) const {
  FS_THROW_UNLESS(encoder_.size() >= 1 && !mlp_.layers().empty(), path,
                  ": cannot save an empty (default-constructed) OtnetModel");
  const int d = encoder_.size(), w = encoder_.width(), h = encoder_.height();
  std::vector<std::uint8_t> db;
  db.reserve(static_cast<std::size_t>(d) * w * h);
  for (const BinaryGrid& g : encoder_.database())
    db.insert(db.end(), g.cells.begin(), g.cells.end());
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kOtnetModelType, config_yaml, seed);
    f->SetAttr("/model", "components", std::int64_t{head_.components});
    f->SetAttr("/model", "family", std::string(ToString(family_)));
    f->SetAttr("/model", "num_basis", std::int64_t{basis_.size()});
    f->SetAttr("/model", "gamma", basis_.gamma());
    f->SetAttr("/model", "ridge", basis_.ridge());
    f->SetAttr("/model", "length_scale", encoder_.length_scale());
    f->SetAttr("/model", "width", std::int64_t{w});
    f->SetAttr("/model", "height", std::int64_t{h});
    f->SetAttr("/model", "database_size", std::int64_t{d});
    f->Write(
        "/model/database", db.data(),
        {static_cast<std::size_t>(d), static_cast<std::size_t>(h), static_cast<std::size_t>(w)});
    f->Write("/model/log_scale_offset", log_scale_offset_.data(),
             {static_cast<std::size_t>(log_scale_offset_.size())});
    mlp_.Save(f, "/weights/", LayerNames(static_cast<int>(mlp_.layers().size())));
  });
}

OtnetModel::Workspace OtnetModel::MakeWorkspace(int max_count, int points) const {
  FS_THROW_UNLESS(max_count >= 1, "OtnetModel::MakeWorkspace: max_count ", max_count,
                  " must be >= 1");
  FS_THROW_UNLESS(points >= 2, "OtnetModel::MakeWorkspace: points ", points, " must be >= 2");
  FS_THROW_UNLESS(!mlp_.layers().empty(), "OtnetModel::MakeWorkspace: empty model");
  const int q = head_.components, n = head_.weights;
  Workspace ws;
  ws.encoder = encoder_.MakeWorkspace();
  ws.mlp = mlp_.MakeWorkspace();
  ws.phi = Eigen::VectorXd::Zero(encoder_.size());
  ws.phi_f = Eigen::VectorXf::Zero(encoder_.size());
  for (Mixture* m : {&ws.mixture, &ws.conditioned}) {
    m->alpha = Eigen::VectorXd::Constant(q, 1.0 / q);
    m->mean = Eigen::MatrixXd::Zero(q, n);
    m->scale = Eigen::MatrixXd::Ones(q, n);
    m->gain = Eigen::MatrixXd::Zero(q, n);
    m->family = family_;
  }
  ws.taus = UniformTaus(points);
  ws.design = basis_.Design(ws.taus);
  ws.w = Eigen::VectorXd::Zero(n);
  ws.cumulative = Eigen::VectorXd::Zero(q);
  ws.generated.assign(static_cast<std::size_t>(max_count), Eigen::MatrixX2d::Zero(points, 2));
  return ws;
}

const Mixture& OtnetModel::Predict(const BinaryGrid& map, Workspace* ws) const {
  ws->phi.resize(encoder_.size());
  encoder_.Encode(map, &ws->encoder, ws->phi);
  PredictFromFeatures(ws->phi, ws, &ws->mixture);
  return ws->mixture;
}

void OtnetModel::PredictFromFeatures(const Eigen::Ref<const Eigen::VectorXd>& phi, Workspace* ws,
                                     Mixture* out) const {
  FS_THROW_UNLESS(phi.size() == encoder_.size(), "OtnetModel::PredictFromFeatures: phi has ",
                  phi.size(), " entries, the database ", encoder_.size());
  FS_THROW_UNLESS(phi.allFinite(), "OtnetModel::PredictFromFeatures: phi is not finite");
  ws->phi_f = phi.cast<float>();
  const Eigen::Ref<const Eigen::VectorXf> y = mlp_.Forward(ws->phi_f, &ws->mlp);
  const int qn = head_.components, n = head_.weights;
  for (Eigen::Index i = 0; i < y.size(); ++i)
    FS_THROW_UNLESS(std::isfinite(y[i]), "OtnetModel::PredictFromFeatures: network output ", i,
                    " is ", y[i]);
  out->alpha.resize(qn);
  out->mean.resize(qn, n);
  out->scale.resize(qn, n);
  out->gain.setZero(qn, n);
  // Stable softmax: shift by the largest logit.
  double top = -std::numeric_limits<double>::infinity();
  for (int q = 0; q < qn; ++q) top = std::max(top, static_cast<double>(y[head_.LogitOffset() + q]));
  double total = 0;
  for (int q = 0; q < qn; ++q) {
    out->alpha[q] = std::exp(static_cast<double>(y[head_.LogitOffset() + q]) - top);
    total += out->alpha[q];
  }
  out->alpha /= total;
  for (int q = 0; q < qn; ++q) {
    for (int j = 0; j < n; ++j) {
      out->mean(q, j) = y[head_.MeanOffset(q) + j];
      const double o = log_scale_offset_[j];
      const double z = std::clamp(static_cast<double>(y[head_.LogScaleOffset(q) + j]) - o,
                                  OtnetHead::kLogScaleMin, OtnetHead::kLogScaleMax);
      out->scale(q, j) = std::exp(z + o);
    }
  }
  out->family = family_;
  out->conditioned = false;
  out->start.setZero();
}

void OtnetModel::ComponentMarginals(const Mixture& m, int q, const Eigen::VectorXd& taus,
                                    Eigen::MatrixX2d* mean, Eigen::MatrixXd* cov_x,
                                    Eigen::MatrixXd* cov_y) const {
  CheckMixture(m, head_.components, head_.weights, "OtnetModel::ComponentMarginals");
  FS_THROW_UNLESS(q >= 0 && q < head_.components, "OtnetModel::ComponentMarginals: component ", q,
                  " out of range [0, ", head_.components, ")");
  CheckTaus(taus, "OtnetModel::ComponentMarginals");
  const TimeBasis& b = basis_.time_basis();
  const int size = b.size();
  const Eigen::MatrixXd k = basis_.Design(taus);  // [L x M]
  mean->resize(taus.size(), 2);
  Eigen::VectorXd v, vk0;
  double c = 0;
  for (int d = 0; d < 2; ++d) {
    mean->col(d) = k * m.mean.row(q).segment(d * size, size).transpose();
    WeightMoments(b, m, q, d, &v, &vk0, &c);
    // K Var K' (thesis: Sigma-hat = K Sigma K'); conditioned: K (Var - Var k0 k0' Var / c) K'.
    Eigen::MatrixXd cov = k * v.asDiagonal() * k.transpose();
    if (m.conditioned) {
      const Eigen::VectorXd u = k * vk0;
      cov.noalias() -= u * u.transpose() / c;
    }
    (d == 0 ? *cov_x : *cov_y) = 0.5 * (cov + cov.transpose());
  }
}

PerTimeDensity OtnetModel::Density(const Mixture& m, const Eigen::VectorXd& taus) const {
  CheckMixture(m, head_.components, head_.weights, "OtnetModel::Density");
  CheckTaus(taus, "OtnetModel::Density");
  const TimeBasis& b = basis_.time_basis();
  const int size = b.size();
  const Eigen::MatrixXd k = basis_.Design(taus);
  const Eigen::Index l = taus.size();
  PerTimeDensity out;
  int kept = 0;
  for (int q = 0; q < head_.components; ++q) kept += m.alpha[q] > 0;
  out.weights.resize(kept);
  Eigen::VectorXd v, vk0;
  double c = 0;
  int i = 0;
  for (int q = 0; q < head_.components; ++q) {
    if (!(m.alpha[q] > 0)) continue;
    out.weights[i++] = m.alpha[q];
    Eigen::MatrixX2d mean(l, 2);
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(l, 3);  // (var_x, cov_xy = 0, var_y)
    for (int d = 0; d < 2; ++d) {
      mean.col(d) = k * m.mean.row(q).segment(d * size, size).transpose();
      WeightMoments(b, m, q, d, &v, &vk0, &c);
      // The diagonal of the marginal covariance only (per-tau density).
      Eigen::VectorXd var = k.array().square().matrix() * v;
      if (m.conditioned) var -= (k * vk0).array().square().matrix() / c;
      cov.col(2 * d) = var.cwiseMax(0.0);  // rounding at a conditioned tau = 0 can go below 0
    }
    out.means.push_back(std::move(mean));
    out.covs.push_back(std::move(cov));
  }
  out.weights /= out.weights.sum();
  return out;
}

void OtnetModel::ConditionOnStart(const Mixture& prior, const Eigen::Vector2d& start,
                                  ComponentSelection selection, Mixture* out) const {
  FS_THROW_UNLESS(start.allFinite(), "OtnetModel::ConditionOnStart: start (", start.x(), ", ",
                  start.y(), ") is not finite");
  FS_THROW_UNLESS(!prior.conditioned,
                  "OtnetModel::ConditionOnStart: the prior is already "
                  "conditioned (on (",
                  prior.start.x(), ", ", prior.start.y(), "))");
  FS_THROW_UNLESS(out != &prior, "OtnetModel::ConditionOnStart: out must not be the prior");
  CheckMixture(prior, head_.components, head_.weights, "OtnetModel::ConditionOnStart: prior");
  const TimeBasis& b = basis_.time_basis();
  const int qn = head_.components, size = b.size();
  out->alpha.resize(qn);
  out->mean.resize(qn, head_.weights);
  out->gain.resize(qn, head_.weights);
  out->scale = prior.scale;
  out->family = prior.family;
  for (int q = 0; q < qn; ++q) {
    // log alpha_q + log N(s; mu_q(0), Sigma_q(0)), x and y independent within a component.
    double log_weight =
        prior.alpha[q] > 0 ? std::log(prior.alpha[q]) : -std::numeric_limits<double>::infinity();
    for (int d = 0; d < 2; ++d) {
      const StartMoments s0 = StartOf(b, prior, q, d);
      const double r = start[d] - s0.mean;
      log_weight -= 0.5 * (kLogTwoPi + std::log(s0.variance) + r * r / s0.variance);
      // g = Var k0 / (k0' Var k0); mu_c = mu + g (s - k0' mu).
      const double factor = VarianceFactor(prior.family);
      for (int j = 0; j < size; ++j) {
        const int idx = d * size + j;
        const double sj = prior.scale(q, idx);
        const double g = factor * sj * sj * BasisAtStart(b, j) / s0.variance;
        out->gain(q, idx) = g;
        out->mean(q, idx) = prior.mean(q, idx) + g * r;
      }
    }
    out->alpha[q] = log_weight;  // normalised below
  }
  int best = -1;
  for (int q = 0; q < qn; ++q)
    if (std::isfinite(out->alpha[q]) && (best < 0 || out->alpha[q] > out->alpha[best])) best = q;
  FS_THROW_UNLESS(best >= 0, "OtnetModel::ConditionOnStart: start (", start.x(), ", ", start.y(),
                  ") has zero likelihood under every component");
  if (selection == ComponentSelection::kNearest) {
    out->alpha.setZero();
    out->alpha[best] = 1.0;
  } else {
    // Log-sum-exp around the largest log weight.
    const double top = out->alpha[best];
    double total = 0;
    for (int q = 0; q < qn; ++q) {
      out->alpha[q] = std::isfinite(out->alpha[q]) ? std::exp(out->alpha[q] - top) : 0.0;
      total += out->alpha[q];
    }
    out->alpha /= total;
  }
  out->conditioned = true;
  out->start = start;
}

GenerateStats OtnetModel::Generate(const BinaryGrid& map, const Mixture& mixture,
                                   const GenerateOptions& options, std::mt19937_64* rng,
                                   Workspace* ws) const {
  const int capacity_points = static_cast<int>(std::min(ws->taus.size(), ws->design.rows()));
  FS_THROW_UNLESS(options.count >= 1 && options.count <= static_cast<int>(ws->generated.size()),
                  "OtnetModel::Generate: options.count ", options.count, " outside 1 to ",
                  ws->generated.size(), " (the workspace's max_count)");
  FS_THROW_UNLESS(options.points >= 2 && options.points <= capacity_points,
                  "OtnetModel::Generate: options.points ", options.points, " outside 2 to ",
                  capacity_points, " (the workspace's points)");
  FS_THROW_UNLESS(ws->design.cols() == basis_.size(),
                  "OtnetModel::Generate: the workspace's design has ", ws->design.cols(),
                  " columns, the basis ", basis_.size(), " functions");
  FS_THROW_UNLESS(options.max_attempts >= options.count,
                  "OtnetModel::Generate: options.max_attempts ", options.max_attempts,
                  " is below options.count ", options.count);
  FS_THROW_UNLESS(std::isfinite(options.check_step) && options.check_step > 0,
                  "OtnetModel::Generate: options.check_step ", options.check_step,
                  " must be positive and finite");
  FS_THROW_UNLESS(map.width >= 1 && map.height >= 1 &&
                      map.cells.size() == static_cast<std::size_t>(map.width) * map.height,
                  "OtnetModel::Generate: map of ", map.width, "x", map.height, " with ",
                  map.cells.size(), " cells");
  CheckMixture(mixture, head_.components, head_.weights, "OtnetModel::Generate");
  if (mixture.conditioned) {
    FS_THROW_UNLESS(!map.OccupiedAt(mixture.start.x(), mixture.start.y()),
                    "OtnetModel::Generate: the start point (", mixture.start.x(), ", ",
                    mixture.start.y(), ") is ",
                    mixture.start.x() >= 0 && mixture.start.y() >= 0 &&
                            mixture.start.x() < map.width && mixture.start.y() < map.height
                        ? "in an occupied cell"
                        : "outside the map",
                    " (", map.width, "x", map.height, ")");
  }
  const TimeBasis& b = basis_.time_basis();
  const int size = b.size(), points = options.points, qn = head_.components;
  ws->w.resize(head_.weights);
  ws->cumulative.resize(qn);
  // taus = UniformTaus(points) and K(taus) in the first `points` rows of the workspace.
  for (int i = 0; i < points; ++i) {
    ws->taus[i] = static_cast<double>(i) / (points - 1);
    for (int j = 0; j < size; ++j) {
      const double d = ws->taus[i] - b.centres()[j];
      ws->design(i, j) = std::exp(-b.gamma() * d * d);
    }
  }
  double running = 0;
  int last_positive = 0;  // the fallback when rounding puts u at the very top
  for (int q = 0; q < qn; ++q) {
    ws->cumulative[q] = running += mixture.alpha[q];
    if (mixture.alpha[q] > 0) last_positive = q;
  }

  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::exponential_distribution<double> exponential;
  const bool laplace = mixture.family == MixtureFamily::kLaplace;
  const auto design = ws->design.topRows(points);
  GenerateStats stats;
  while (stats.accepted < options.count && stats.attempts < options.max_attempts) {
    ++stats.attempts;
    // The component: the first q with u < cumulative[q] (zero-weight components are never hit).
    const double u = uniform(*rng) * ws->cumulative[qn - 1];
    int q = last_positive;
    for (int c = 0; c < qn; ++c) {
      if (u < ws->cumulative[c] && mixture.alpha[c] > 0) {
        q = c;
        break;
      }
    }
    for (int j = 0; j < head_.weights; ++j) {
      // Standard Laplace = Exp(1) with a random sign.
      const double eps = laplace ? ((*rng)() & 1 ? 1.0 : -1.0) * exponential(*rng) : normal(*rng);
      ws->w[j] = mixture.mean(q, j) + mixture.scale(q, j) * eps;
    }
    if (mixture.conditioned) {
      // w_z += g_z (s_z - k0' w_z): the rank-one correction that pins z(0) to the start.
      for (int d = 0; d < 2; ++d) {
        double z0 = 0;
        for (int j = 0; j < size; ++j) z0 += BasisAtStart(b, j) * ws->w[d * size + j];
        const double r = mixture.start[d] - z0;
        for (int j = 0; j < size; ++j) ws->w[d * size + j] += mixture.gain(q, d * size + j) * r;
      }
    }
    Eigen::MatrixX2d& traj = ws->generated[static_cast<std::size_t>(stats.accepted)];
    traj.resize(points, 2);  // no allocation when it already has `points` rows
    traj.col(0).noalias() = design * ws->w.head(size);
    traj.col(1).noalias() = design * ws->w.tail(size);
    if (options.reject_collisions && TrajectoryCollides(map, traj, options.check_step)) {
      ++stats.rejected;
      continue;
    }
    ++stats.accepted;
  }
  return stats;
}

}  // namespace foresight::otnet
