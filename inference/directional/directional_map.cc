#include "inference/directional/directional_map.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::directional {

const char* VariantName(Variant v) { return v == Variant::kSpatial ? "spatial" : "spatiotemporal"; }

Map::Map(Variant variant, const FeatureConfig& features, Lstm lstm, Heads heads, double max_kappa)
    : variant_(variant),
      features_(features),
      lstm_(std::move(lstm)),
      heads_(std::move(heads)),
      log_kappa_max_(std::log(max_kappa)) {
  Check();
}

void Map::Check() const {
  const auto R = heads_.alpha_b.size();
  const Eigen::Index d =
      variant_ == Variant::kSpatial ? features_.spatial_size() : lstm_.hidden_size();
  FS_THROW_UNLESS(R >= 1 && heads_.mu_b.size() == R && heads_.kappa_b.size() == R,
                  "directional map: heads have ", heads_.alpha_b.size(), ", ", heads_.mu_b.size(),
                  ", ", heads_.kappa_b.size(), " outputs; expected R >= 1 each");
  for (const Eigen::MatrixXf* w : {&heads_.alpha_w, &heads_.mu_w, &heads_.kappa_w})
    FS_THROW_UNLESS(w->rows() == R && w->cols() == d, "directional map: a head weight is ",
                    w->rows(), " x ", w->cols(), ", expected ", R, " x ", d, " (",
                    VariantName(variant_), ")");
  if (variant_ == Variant::kSpatiotemporal)
    FS_THROW_UNLESS(lstm_.input_size() == features_.spatial_size(),
                    "directional map: the LSTM takes ", lstm_.input_size(),
                    " inputs, the features have M_s = ", features_.spatial_size());
  FS_THROW_UNLESS(std::isfinite(log_kappa_max_) && log_kappa_max_ > kDirectionalLogKappaMin,
                  "directional map: max kappa ", std::exp(log_kappa_max_),
                  " must be finite and above exp(", kDirectionalLogKappaMin, ")");
  FS_THROW_UNLESS(heads_.alpha_w.allFinite() && heads_.mu_w.allFinite() &&
                      heads_.kappa_w.allFinite() && heads_.alpha_b.allFinite() &&
                      heads_.mu_b.allFinite() && heads_.kappa_b.allFinite(),
                  "directional map: non-finite head weights");
}

Map Map::Load(const std::string& path) {
  const Artifact art = Artifact::Open(path, kModelType);
  const h5::File& f = art.file();
  Map m;
  const std::string variant = f.GetStringAttr("/model", "variant");
  FS_THROW_UNLESS(variant == "spatiotemporal" || variant == "spatial", path, ": unknown variant '",
                  variant, "' (expected spatiotemporal or spatial)");
  m.variant_ = variant == "spatial" ? Variant::kSpatial : Variant::kSpatiotemporal;
  FeatureConfig fc;
  const std::string g = "/model/features";
  fc.x_min = art.DoubleAttr(g, "x_min", -1e12, 1e12);
  fc.x_max = art.DoubleAttr(g, "x_max", -1e12, 1e12);
  fc.y_min = art.DoubleAttr(g, "y_min", -1e12, 1e12);
  fc.y_max = art.DoubleAttr(g, "y_max", -1e12, 1e12);
  fc.cells_x = art.IntAttr(g, "cells_x", 1, 10000000);
  fc.cells_y = art.IntAttr(g, "cells_y", 1, 10000000);
  fc.length_scale = art.DoubleAttr(g, "length_scale", -1e12, 1e12);
  fc.t_min = art.DoubleAttr(g, "t_min", -1e12, 1e12);
  fc.t_max = art.DoubleAttr(g, "t_max", -1e12, 1e12);
  fc.time_points = art.IntAttr(g, "time_points", 1, 10000000);
  fc.time_length_scale = art.DoubleAttr(g, "time_length_scale", -1e12, 1e12);
  fc.cutoff = art.DoubleAttr(g, "cutoff", -1e12, 1e12);
  FS_THROW_UNLESS(fc.cells_x >= 1 && fc.cells_y >= 1 && fc.time_points >= 1 &&
                      static_cast<double>(fc.cells_x) * fc.cells_y <= 1e7,
                  path, ": implausible inducing grid ", fc.cells_x, " x ", fc.cells_y, " x ",
                  fc.time_points);
  try {
    m.features_ = Features(fc);
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
  m.log_kappa_max_ = art.DoubleAttr("/model", "log_kappa_max", -1e3, 1e3);
  const auto R = art.IntAttr("/model", "components", 1, 1000);
  FS_THROW_UNLESS(R >= 1 && R <= 1000, path, ": implausible number of components ", R);
  auto read_head = [&](const std::string& name, Eigen::MatrixXf* w, Eigen::VectorXf* b) {
    *w = f.ReadMatrixF("/weights/" + name + "/weight", R, -1);
    *b = f.ReadMatrixF("/weights/" + name + "/bias", R, 1).col(0);
  };
  read_head("alpha", &m.heads_.alpha_w, &m.heads_.alpha_b);
  read_head("mu", &m.heads_.mu_w, &m.heads_.mu_b);
  read_head("kappa", &m.heads_.kappa_w, &m.heads_.kappa_b);
  if (m.variant_ == Variant::kSpatiotemporal) m.lstm_ = Lstm::Load(f, "/weights/lstm/");
  try {
    m.Check();
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
  return m;
}

namespace {
/// A 1-d float dataset [n] (biases; docs/artifact_schema.md).
void WriteVector(h5::File* f, const std::string& name, const Eigen::VectorXf& v) {
  f->Write(name, v.data(), {static_cast<std::size_t>(v.size())});
}
}  // namespace

void Map::Save(const std::string& path, const std::string& config_yaml, std::int64_t seed) const {
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kModelType, config_yaml, seed);
    const bool temporal = variant_ == Variant::kSpatiotemporal;
    f->SetAttr("/model", "variant", std::string(VariantName(variant_)));
    f->SetAttr("/model", "components", static_cast<std::int64_t>(components()));
    f->SetAttr("/model", "hidden", static_cast<std::int64_t>(temporal ? lstm_.hidden_size() : 0));
    f->SetAttr("/model", "log_kappa_min", kDirectionalLogKappaMin);
    f->SetAttr("/model", "log_kappa_max", log_kappa_max_);
    const FeatureConfig& c = features_.config();
    const std::string g = "/model/features";
    f->SetAttr(g, "x_min", c.x_min);
    f->SetAttr(g, "x_max", c.x_max);
    f->SetAttr(g, "y_min", c.y_min);
    f->SetAttr(g, "y_max", c.y_max);
    f->SetAttr(g, "cells_x", static_cast<std::int64_t>(c.cells_x));
    f->SetAttr(g, "cells_y", static_cast<std::int64_t>(c.cells_y));
    f->SetAttr(g, "length_scale", c.length_scale);
    f->SetAttr(g, "t_min", c.t_min);
    f->SetAttr(g, "t_max", c.t_max);
    f->SetAttr(g, "time_points", static_cast<std::int64_t>(c.time_points));
    f->SetAttr(g, "time_length_scale", c.time_length_scale);
    f->SetAttr(g, "cutoff", c.cutoff);
    if (temporal) {
      const LstmWeights& w = lstm_.weights();
      f->WriteMatrix("/weights/lstm/weight_ih_l0", w.weight_ih);
      f->WriteMatrix("/weights/lstm/weight_hh_l0", w.weight_hh);
      WriteVector(f, "/weights/lstm/bias_ih_l0", w.bias_ih);
      WriteVector(f, "/weights/lstm/bias_hh_l0", w.bias_hh);
    }
    f->WriteMatrix("/weights/alpha/weight", heads_.alpha_w);
    WriteVector(f, "/weights/alpha/bias", heads_.alpha_b);
    f->WriteMatrix("/weights/mu/weight", heads_.mu_w);
    WriteVector(f, "/weights/mu/bias", heads_.mu_b);
    f->WriteMatrix("/weights/kappa/weight", heads_.kappa_w);
    WriteVector(f, "/weights/kappa/bias", heads_.kappa_b);
  });
}

Map::Workspace Map::MakeWorkspace() const {
  Workspace ws;
  const int R = components();
  if (variant_ == Variant::kSpatiotemporal) {
    ws.lstm = lstm_.MakeWorkspace();
    ws.proj = Eigen::VectorXf::Zero(4 * lstm_.hidden_size());
  }
  ws.phi_s = Eigen::VectorXf::Zero(features_.spatial_size());
  ws.phi_t = Eigen::VectorXf::Zero(features_.time_size());
  ws.raw = Eigen::VectorXf::Zero(3 * R);
  ws.alpha = Eigen::VectorXd::Zero(R);
  ws.mu = Eigen::VectorXd::Zero(R);
  ws.kappa = Eigen::VectorXd::Zero(R);
  return ws;
}

void Map::RawOutput(double x, double y, double t, Workspace* ws) const {
  FS_THROW_UNLESS(std::isfinite(x) && std::isfinite(y) && std::isfinite(t),
                  "directional map: query (", x, ", ", y, ", ", t, ") is not finite");
  const int R = components();
  const int cx = features_.config().cells_x;
  const Features::Window w = features_.SpatialWindow(x, y);
  auto head = [&](int r, const Eigen::MatrixXf& W, const Eigen::VectorXf& b, int offset,
                  const Eigen::Ref<const Eigen::VectorXf>& z) {
    ws->raw[offset + r] = W.row(r).dot(z) + b[r];
  };
  if (variant_ == Variant::kSpatial) {
    // Heads on the sparse features: z = b + sum_j phi_j W[:, j].
    for (int r = 0; r < R; ++r) {
      ws->raw[r] = heads_.alpha_b[r];
      ws->raw[R + r] = heads_.mu_b[r];
      ws->raw[2 * R + r] = heads_.kappa_b[r];
    }
    for (int iy = w.iy0; iy < w.iy1; ++iy)
      for (int ix = w.ix0; ix < w.ix1; ++ix) {
        const float phi = static_cast<float>(features_.SpatialKernel(x, y, ix, iy));
        if (phi == 0.0f) continue;
        const int j = iy * cx + ix;
        for (int r = 0; r < R; ++r) {
          ws->raw[r] += phi * heads_.alpha_w(r, j);
          ws->raw[R + r] += phi * heads_.mu_w(r, j);
          ws->raw[2 * R + r] += phi * heads_.kappa_w(r, j);
        }
      }
    return;
  }
  // Spatiotemporal: step k's input is phi_s * phi_t[k], so W_ih x_k = phi_t[k] (W_ih phi_s).
  ws->proj.setZero();
  const Eigen::MatrixXf& wih = lstm_.weights().weight_ih;
  for (int iy = w.iy0; iy < w.iy1; ++iy)
    for (int ix = w.ix0; ix < w.ix1; ++ix) {
      const float phi = static_cast<float>(features_.SpatialKernel(x, y, ix, iy));
      if (phi != 0.0f) ws->proj.noalias() += phi * wih.col(iy * cx + ix);
    }
  features_.Temporal(t, ws->phi_t);
  lstm_.Reset(&ws->lstm);
  for (int k = 0; k < features_.time_size(); ++k)
    lstm_.StepProjected(ws->proj, ws->phi_t[k], &ws->lstm);
  for (int r = 0; r < R; ++r) {
    head(r, heads_.alpha_w, heads_.alpha_b, 0, ws->lstm.h);
    head(r, heads_.mu_w, heads_.mu_b, R, ws->lstm.h);
    head(r, heads_.kappa_w, heads_.kappa_b, 2 * R, ws->lstm.h);
  }
}

void Map::QueryOne(double x, double y, double t, Workspace* ws) const {
  RawOutput(x, y, t, ws);
  const int R = components();
  double mx = -INFINITY;
  for (int r = 0; r < R; ++r) mx = std::max(mx, static_cast<double>(ws->raw[r]));
  double norm = 0;
  for (int r = 0; r < R; ++r) norm += ws->alpha[r] = std::exp(static_cast<double>(ws->raw[r]) - mx);
  ws->alpha /= norm;
  for (int r = 0; r < R; ++r) {
    ws->mu[r] = WrapAngle(static_cast<double>(ws->raw[R + r]));
    ws->kappa[r] = std::exp(std::clamp(static_cast<double>(ws->raw[2 * R + r]),
                                       kDirectionalLogKappaMin, log_kappa_max_));
  }
}

void Map::Query(const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::VectorXd>& t, Workspace* ws,
                VonMisesMixtureBatch* out) const {
  FS_THROW_UNLESS(x.size() == y.size() && x.size() == t.size(), "directional map: query sizes x ",
                  x.size(), ", y ", y.size(), ", t ", t.size(), " differ");
  const int R = components();
  out->Resize(x.size(), R);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    QueryOne(x[i], y[i], t[i], ws);
    out->alpha.row(i) = ws->alpha.transpose();
    out->mu.row(i) = ws->mu.transpose();
    out->kappa.row(i) = ws->kappa.transpose();
  }
}

void Map::Density(const Eigen::Ref<const Eigen::VectorXd>& x,
                  const Eigen::Ref<const Eigen::VectorXd>& y,
                  const Eigen::Ref<const Eigen::VectorXd>& t,
                  const Eigen::Ref<const Eigen::VectorXd>& theta, Workspace* ws,
                  Eigen::Ref<Eigen::VectorXd> density) const {
  FS_THROW_UNLESS(x.size() == y.size() && x.size() == t.size() && x.size() == theta.size() &&
                      density.size() == x.size(),
                  "directional map: density sizes x ", x.size(), ", y ", y.size(), ", t ", t.size(),
                  ", theta ", theta.size(), ", out ", density.size(), " differ");
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    FS_THROW_UNLESS(std::isfinite(theta[i]), "directional map: heading ", i, " is not finite");
    QueryOne(x[i], y[i], t[i], ws);
    density[i] = std::exp(VonMisesMixtureLogDensity(theta[i], ws->alpha, ws->mu, ws->kappa));
  }
}

}  // namespace foresight::directional
