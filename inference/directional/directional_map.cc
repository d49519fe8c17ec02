#include "inference/directional/directional_map.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight {

const char* VariantName(DirectionalVariant v) {
  return v == DirectionalVariant::kSpatial ? "spatial" : "spatiotemporal";
}

DirectionalMap::DirectionalMap(DirectionalVariant variant, const DirectionalFeatureConfig& features, Lstm lstm,
                               DirectionalHeads heads, double max_kappa)
    : variant_(variant), features_(features), lstm_(std::move(lstm)), heads_(std::move(heads)),
      log_kappa_max_(std::log(max_kappa)) {
  Check();
}

void DirectionalMap::Check() const {
  const auto R = heads_.alpha_b.size();
  const Eigen::Index d = variant_ == DirectionalVariant::kSpatial ? features_.spatial_size() : lstm_.hidden_size();
  FS_THROW_UNLESS(R >= 1 && heads_.mu_b.size() == R && heads_.kappa_b.size() == R,
                  "directional map: heads have ", heads_.alpha_b.size(), ", ", heads_.mu_b.size(), ", ",
                  heads_.kappa_b.size(), " outputs; expected R >= 1 each");
  for (const Eigen::MatrixXf* w : {&heads_.alpha_w, &heads_.mu_w, &heads_.kappa_w})
    FS_THROW_UNLESS(w->rows() == R && w->cols() == d, "directional map: a head weight is ", w->rows(), " x ",
                    w->cols(), ", expected ", R, " x ", d, " (", VariantName(variant_), ")");
  if (variant_ == DirectionalVariant::kSpatiotemporal)
    FS_THROW_UNLESS(lstm_.input_size() == features_.spatial_size(), "directional map: the LSTM takes ",
                    lstm_.input_size(), " inputs, the features have M_s = ", features_.spatial_size());
  FS_THROW_UNLESS(std::isfinite(log_kappa_max_) && log_kappa_max_ > kDirectionalLogKappaMin,
                  "directional map: max kappa ", std::exp(log_kappa_max_), " must be finite and above exp(",
                  kDirectionalLogKappaMin, ")");
  FS_THROW_UNLESS(heads_.alpha_w.allFinite() && heads_.mu_w.allFinite() && heads_.kappa_w.allFinite() &&
                      heads_.alpha_b.allFinite() && heads_.mu_b.allFinite() && heads_.kappa_b.allFinite(),
                  "directional map: non-finite head weights");
}

DirectionalMap DirectionalMap::Load(const std::string& path) {
  const Artifact art = Artifact::Open(path, kDirectionalModelType);
  const h5::File& f = art.file();
  DirectionalMap m;
  const std::string variant = f.GetStringAttr("/model", "variant");
  FS_THROW_UNLESS(variant == "spatiotemporal" || variant == "spatial", path, ": unknown variant '", variant,
                  "' (expected spatiotemporal or spatial)");
  m.variant_ = variant == "spatial" ? DirectionalVariant::kSpatial : DirectionalVariant::kSpatiotemporal;
  DirectionalFeatureConfig fc;
  const std::string g = "/model/features";
  fc.x_min = f.GetDoubleAttr(g, "x_min");
  fc.x_max = f.GetDoubleAttr(g, "x_max");
  fc.y_min = f.GetDoubleAttr(g, "y_min");
  fc.y_max = f.GetDoubleAttr(g, "y_max");
  fc.cells_x = static_cast<int>(f.GetIntAttr(g, "cells_x"));
  fc.cells_y = static_cast<int>(f.GetIntAttr(g, "cells_y"));
  fc.length_scale = f.GetDoubleAttr(g, "length_scale");
  fc.t_min = f.GetDoubleAttr(g, "t_min");
  fc.t_max = f.GetDoubleAttr(g, "t_max");
  fc.time_points = static_cast<int>(f.GetIntAttr(g, "time_points"));
  fc.time_length_scale = f.GetDoubleAttr(g, "time_length_scale");
  fc.cutoff = f.GetDoubleAttr(g, "cutoff");
  FS_THROW_UNLESS(fc.cells_x >= 1 && fc.cells_y >= 1 && fc.time_points >= 1 &&
                      static_cast<double>(fc.cells_x) * fc.cells_y <= 1e7,
                  path, ": implausible inducing grid ", fc.cells_x, " x ", fc.cells_y, " x ", fc.time_points);
  try {
    m.features_ = DirectionalFeatures(fc);
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
  m.log_kappa_max_ = f.GetDoubleAttr("/model", "log_kappa_max");
  const auto R = f.GetIntAttr("/model", "components");
  FS_THROW_UNLESS(R >= 1 && R <= 1000, path, ": implausible number of components ", R);
  auto read_head = [&](const std::string& name, Eigen::MatrixXf* w, Eigen::VectorXf* b) {
    *w = f.ReadMatrixF("/weights/" + name + "/weight", R, -1);
    *b = f.ReadMatrixF("/weights/" + name + "/bias", R, 1).col(0);
  };
  read_head("alpha", &m.heads_.alpha_w, &m.heads_.alpha_b);
  read_head("mu", &m.heads_.mu_w, &m.heads_.mu_b);
  read_head("kappa", &m.heads_.kappa_w, &m.heads_.kappa_b);
  if (m.variant_ == DirectionalVariant::kSpatiotemporal) m.lstm_ = Lstm::Load(f, "/weights/lstm/");
  try {
    m.Check();
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
  return m;
}

DirectionalMap::Workspace DirectionalMap::MakeWorkspace() const {
  Workspace ws;
  const int R = components();
  if (variant_ == DirectionalVariant::kSpatiotemporal) {
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

void DirectionalMap::RawOutput(double x, double y, double t, Workspace* ws) const {
  FS_THROW_UNLESS(std::isfinite(x) && std::isfinite(y) && std::isfinite(t), "directional map: query (", x, ", ",
                  y, ", ", t, ") is not finite");
  const int R = components();
  const int cx = features_.config().cells_x;
  const DirectionalFeatures::Window w = features_.SpatialWindow(x, y);
  auto head = [&](int r, const Eigen::MatrixXf& W, const Eigen::VectorXf& b, int offset,
                  const Eigen::Ref<const Eigen::VectorXf>& z) { ws->raw[offset + r] = W.row(r).dot(z) + b[r]; };
  if (variant_ == DirectionalVariant::kSpatial) {
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
  for (int k = 0; k < features_.time_size(); ++k) lstm_.StepProjected(ws->proj, ws->phi_t[k], &ws->lstm);
  for (int r = 0; r < R; ++r) {
    head(r, heads_.alpha_w, heads_.alpha_b, 0, ws->lstm.h);
    head(r, heads_.mu_w, heads_.mu_b, R, ws->lstm.h);
    head(r, heads_.kappa_w, heads_.kappa_b, 2 * R, ws->lstm.h);
  }
}

void DirectionalMap::QueryOne(double x, double y, double t, Workspace* ws) const {
  RawOutput(x, y, t, ws);
  const int R = components();
  double mx = -INFINITY;
  for (int r = 0; r < R; ++r) mx = std::max(mx, static_cast<double>(ws->raw[r]));
  double norm = 0;
  for (int r = 0; r < R; ++r) norm += ws->alpha[r] = std::exp(static_cast<double>(ws->raw[r]) - mx);
  ws->alpha /= norm;
  for (int r = 0; r < R; ++r) {
    ws->mu[r] = WrapAngle(static_cast<double>(ws->raw[R + r]));
    ws->kappa[r] = std::exp(
        std::clamp(static_cast<double>(ws->raw[2 * R + r]), kDirectionalLogKappaMin, log_kappa_max_));
  }
}

void DirectionalMap::Query(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
                           const Eigen::Ref<const Eigen::VectorXd>& t, Workspace* ws,
                           VonMisesMixtureBatch* out) const {
  FS_THROW_UNLESS(x.size() == y.size() && x.size() == t.size(), "directional map: query sizes x ", x.size(),
                  ", y ", y.size(), ", t ", t.size(), " differ");
  const int R = components();
  out->Resize(x.size(), R);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    QueryOne(x[i], y[i], t[i], ws);
    out->alpha.row(i) = ws->alpha.transpose();
    out->mu.row(i) = ws->mu.transpose();
    out->kappa.row(i) = ws->kappa.transpose();
  }
}

void DirectionalMap::Density(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
                             const Eigen::Ref<const Eigen::VectorXd>& t,
                             const Eigen::Ref<const Eigen::VectorXd>& theta, Workspace* ws,
                             Eigen::Ref<Eigen::VectorXd> density) const {
  FS_THROW_UNLESS(x.size() == y.size() && x.size() == t.size() && x.size() == theta.size() &&
                      density.size() == x.size(),
                  "directional map: density sizes x ", x.size(), ", y ", y.size(), ", t ", t.size(), ", theta ",
                  theta.size(), ", out ", density.size(), " differ");
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    FS_THROW_UNLESS(std::isfinite(theta[i]), "directional map: heading ", i, " is not finite");
    QueryOne(x[i], y[i], t[i], ws);
    density[i] = std::exp(VonMisesMixtureLogDensity(theta[i], ws->alpha, ws->mu, ws->kappa));
  }
}

}  // namespace foresight
