#include "inference/prediction/span_predictor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/ego_frame.h"
#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::span {

// ---------------------------------------------------------------- Predictor

Predictor Predictor::Load(const std::string& path) {
  const Artifact art = Artifact::Open(path, kModelType);
  const h5::File& f = art.file();
  Predictor p;
  p.observed_ = art.IntAttr("/model", "observed", 2, 100000);
  p.seconds_per_step_ = art.DoubleAttr("/model", "seconds_per_step", 1e-6, 3600);
  p.rotate_ = f.GetIntAttr("/model", "rotate_to_heading") != 0;
  p.residual_cv_ = f.HasAttr("/model", "residual_to_constant_velocity") &&
                   f.GetIntAttr("/model", "residual_to_constant_velocity") != 0;
  p.layout_.basis = art.IntAttr("/model", "basis_size", 1, 10000);
  p.layout_.components = art.IntAttr("/model", "components", 1, 64);
  const std::string u_param = f.GetStringAttr("/model", "u_param");
  FS_THROW_UNLESS(u_param == "cholesky" || u_param == "diagonal", path, ": unknown u_param '",
                  u_param, "'");
  p.layout_.u_param = u_param == "cholesky" ? UParam::kCholesky : UParam::kDiagonal;
  FS_THROW_UNLESS(p.observed_ >= 2 && p.layout_.basis >= 1 && p.layout_.components >= 1 &&
                      p.layout_.components <= 64 && p.seconds_per_step_ > 0,
                  path, ": implausible model attributes (observed ", p.observed_, ", basis ",
                  p.layout_.basis, ", components ", p.layout_.components, ")");
  const Eigen::MatrixXd centres = f.ReadMatrixD("/model/basis_centres", p.layout_.basis, 1);
  FS_THROW_UNLESS(centres.allFinite(), path, ": /model/basis_centres has non-finite entries");
  const double gamma = art.DoubleAttr("/model", "basis_gamma", 1e-12, 1e12);
  try {
    p.basis_ = TimeBasis(centres.col(0), gamma);
  } catch (const Error& e) {
    Fail(path, ": ", e.what());
  }
  int in = 2 * p.observed_;
  if (f.Exists("/model/ktm_references")) {
    // KTM input stage: K kernel features of the ego-frame past replace the raw points.
    p.ktm_references_ = f.ReadMatrixD("/model/ktm_references");
    FS_THROW_UNLESS(p.ktm_references_.rows() >= 1 && p.ktm_references_.cols() == in &&
                        p.ktm_references_.allFinite(),
                    path, ": /model/ktm_references is ", p.ktm_references_.rows(), " x ",
                    p.ktm_references_.cols(),
                    ", expected K >= 1 finite rows of 2 x observed = ", in);
    p.ktm_lengthscale_ = art.DoubleAttr("/model", "ktm_lengthscale", 1e-9, 1e9);
    in = static_cast<int>(p.ktm_references_.rows());
  }
  p.input_mean_ = f.ReadMatrixD("/normalisation/input_mean", in, 1).col(0);
  p.input_std_ = f.ReadMatrixD("/normalisation/input_std", in, 1).col(0);
  FS_THROW_UNLESS((p.input_std_.array() > 0).all() && p.input_mean_.allFinite(), path,
                  ": /normalisation has non-positive or non-finite entries");
  // A subnormal std passes "> 0" but turns a finite past into inf/NaN network inputs. Trainers
  // floor it at 1 cm (training/span/pipeline.cc).
  for (Eigen::Index i = 0; i < p.input_std_.size(); ++i)
    FS_THROW_UNLESS(std::isfinite(p.input_std_[i]) && p.input_std_[i] >= 1e-6, path,
                    ": /normalisation/input_std[", i, "] is ", p.input_std_[i],
                    "; expected a finite standard deviation >= 1e-6");
  // A huge mean overflows the float network input (ego-frame metres or KTM features in [0, 1]).
  for (Eigen::Index i = 0; i < p.input_mean_.size(); ++i)
    FS_THROW_UNLESS(std::abs(p.input_mean_[i]) <= 1e6, path, ": /normalisation/input_mean[", i,
                    "] is ", p.input_mean_[i], "; expected a mean from -1e6 to 1e6");
  if (f.HasAttr("/model", "covariance_scale"))
    p.covariance_scale_ = art.DoubleAttr("/model", "covariance_scale", 1e-6, 1e6);
  p.mlp_ = Mlp::LoadListed(f, "/model", "dense_layers", "/weights/");
  FS_THROW_UNLESS(p.mlp_.input_size() == in, path, ": network takes ", p.mlp_.input_size(),
                  " inputs, expected ",
                  p.ktm_references_.size() > 0 ? "K (KTM references) = " : "2 x observed = ", in);
  FS_THROW_UNLESS(p.mlp_.output_size() == p.layout_.Total(), path, ": network gives ",
                  p.mlp_.output_size(), " outputs, the head layout needs ", p.layout_.Total());
  return p;
}

void Predictor::Save(const std::string& path, const PredictorWeights& w,
                     const std::string& config_yaml, std::int64_t seed) {
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kModelType, config_yaml, seed);
    f->SetAttr("/model", "observed", static_cast<std::int64_t>(w.observed));
    f->SetAttr("/model", "predicted", static_cast<std::int64_t>(w.predicted));
    f->SetAttr("/model", "seconds_per_step", w.seconds_per_step);
    f->SetAttr("/model", "rotate_to_heading", static_cast<std::int64_t>(w.rotate_to_heading));
    f->SetAttr("/model", "residual_to_constant_velocity",
               static_cast<std::int64_t>(w.residual_to_constant_velocity));
    f->SetAttr("/model", "basis_size", static_cast<std::int64_t>(w.layout.basis));
    f->SetAttr("/model", "components", static_cast<std::int64_t>(w.layout.components));
    f->SetAttr("/model", "u_param", std::string(UParamName(w.layout.u_param)));
    f->SetAttr("/model", "basis_gamma", w.basis_gamma);
    if (w.covariance_scale != 1.0) f->SetAttr("/model", "covariance_scale", w.covariance_scale);
    f->WriteMatrix("/model/basis_centres", w.basis_centres);
    f->WriteMatrix("/normalisation/input_mean", w.input_mean);
    f->WriteMatrix("/normalisation/input_std", w.input_std);
    w.mlp.SaveListed(f, "/model", "dense_layers", "/weights/", w.layer_names);
    if (w.ktm_references.size() > 0) {
      f->WriteMatrix("/model/ktm_references", w.ktm_references);
      f->SetAttr("/model", "ktm_lengthscale", w.ktm_lengthscale);
    }
  });
}

Predictor::Workspace Predictor::MakeWorkspace() const {
  return {Eigen::VectorXf::Zero(mlp_.input_size()), mlp_.MakeWorkspace(),
          Eigen::VectorXd::Zero(layout_.Total()),
          Eigen::Matrix<double, Eigen::Dynamic, 2>::Zero(observed_, 2),
          Eigen::VectorXd::Zero(2 * observed_)};
}

TrajectoryDistribution Predictor::MakeDistribution() const {
  return TrajectoryDistribution(basis_, layout_.components);
}

namespace {
/// `out` must come from MakeDistribution() of a model with this layout (Predict writes in place).
void CheckOutput(const TrajectoryDistribution& out, const HeadLayout& layout) {
  FS_THROW_UNLESS(out.components() == layout.components && out.basis_size() == layout.basis,
                  "SpanPredictor: the output distribution has ", out.components(),
                  " components over ", out.basis_size(), " basis functions, the model predicts ",
                  layout.components, " over ", layout.basis, " (make it with MakeDistribution())");
}

EgoFrame FrameOf(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
                 bool rotate) {
  return EgoFrame::FromPast(
      static_cast<int>(past.rows()), [&](int i) { return Eigen::Vector2d(past(i, 0), past(i, 1)); },
      rotate);
}
}  // namespace

void Predictor::RawOutput(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
                          Workspace* ws) const {
  FS_THROW_UNLESS(past.rows() == observed_, "SpanPredictor: expected ", observed_,
                  " observed points, got ", past.rows());
  FS_THROW_UNLESS(past.allFinite(), "SpanPredictor: observed track contains NaN or inf");
  const EgoFrame frame = FrameOf(past, rotate_);
  for (int i = 0; i < observed_; ++i)
    ws->ego.segment<2>(2 * i) = frame.ToEgo(Eigen::Vector2d(past(i, 0), past(i, 1)));
  if (ktm_references_.size() == 0) {
    for (int i = 0; i < 2 * observed_; ++i)
      ws->input[i] = static_cast<float>((ws->ego[i] - input_mean_[i]) / input_std_[i]);
  } else {
    // k(q, r) = exp(-d^2 / (2 l^2)), d^2 = (1/p) sum_i |q_i - r_i|^2 (RMS pointwise distance).
    const double scale = 1.0 / (2.0 * observed_ * ktm_lengthscale_ * ktm_lengthscale_);
    for (Eigen::Index k = 0; k < ktm_references_.rows(); ++k) {
      double sq = 0.0;
      for (int i = 0; i < 2 * observed_; ++i) {
        const double d = ws->ego[i] - ktm_references_(k, i);
        sq += d * d;
      }
      ws->input[k] = static_cast<float>((std::exp(-sq * scale) - input_mean_[k]) / input_std_[k]);
    }
  }
  const auto out = mlp_.Forward(ws->input, &ws->mlp);
  ws->raw = out.cast<double>();
}

void Predictor::Predict(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
                        Workspace* ws, TrajectoryDistribution* out) const {
  CheckOutput(*out, layout_);
  RawOutput(past, ws);
  const EgoFrame frame = FrameOf(past, rotate_);
  const Eigen::Matrix2d& rot = frame.rotation;
  const Eigen::VectorXd& z = ws->raw;
  const int m = layout_.basis, R = layout_.components;
  auto clamped_exp = [](double v) {
    return std::exp(std::clamp(v, HeadLayout::kLogDiagMin, HeadLayout::kLogDiagMax));
  };
  out->origin_ = frame.origin;
  if (residual_cv_) {
    const int p = observed_;
    out->velocity_ =
        Eigen::Vector2d(past(p - 1, 0) - past(p - 2, 0), past(p - 1, 1) - past(p - 2, 1)) /
        seconds_per_step_;
  } else {
    out->velocity_.setZero();
  }
  double max_logit = -INFINITY;
  for (int r = 0; r < R; ++r) max_logit = std::max(max_logit, z[layout_.AlphaOffset(r)]);
  double norm = 0.0;
  for (int r = 0; r < R; ++r)
    norm += out->alpha_[r] = std::exp(z[layout_.AlphaOffset(r)] - max_logit);
  out->alpha_ /= norm;
  for (int r = 0; r < R; ++r) {
    const auto k = static_cast<std::size_t>(r);
    // M_world = M_ego R'.
    const int mo = layout_.MeanOffset(r);
    for (int j = 0; j < m; ++j) {
      const Eigen::Vector2d row(z[mo + 2 * j], z[mo + 2 * j + 1]);
      out->mean_[k].row(j).noalias() = (rot * row).transpose();
    }
    Eigen::MatrixXd& lu = out->chol_u_[k];
    const int uo = layout_.UOffset(r);
    if (layout_.u_param == UParam::kDiagonal) {
      for (int i = 0; i < m; ++i) lu(i, i) = clamped_exp(z[uo + i]);
    } else {
      int idx = uo;
      for (int i = 0; i < m; ++i)
        for (int j = 0; j <= i; ++j, ++idx) lu(i, j) = (i == j) ? clamped_exp(z[idx]) : z[idx];
    }
    // V_world = R V_ego R', re-factorised as a lower Cholesky factor.
    const int vo = layout_.VOffset(r);
    Eigen::Matrix2d lv;
    lv << clamped_exp(z[vo]), 0.0, z[vo + 1], clamped_exp(z[vo + 2]);
    const Eigen::Matrix2d v = covariance_scale_ * (rot * (lv * lv.transpose()) * rot.transpose());
    const double l00 = std::sqrt(v(0, 0));
    const double l10 = v(1, 0) / l00;
    const double l11 = std::sqrt(std::max(v(1, 1) - l10 * l10, 1e-300));
    out->chol_v_[k] << l00, 0.0, l10, l11;
  }
}

void Predictor::PredictBatch(const Eigen::Ref<const Eigen::MatrixXd>& past_rows, Workspace* ws,
                             std::vector<TrajectoryDistribution>* out) const {
  FS_THROW_UNLESS(past_rows.cols() == 2 * observed_, "SpanPredictor: batch rows have ",
                  past_rows.cols(), " entries, expected 2 x observed = ", 2 * observed_);
  FS_THROW_UNLESS(out->size() >= static_cast<std::size_t>(past_rows.rows()),
                  "SpanPredictor: output holds ", out->size(), " distributions for ",
                  past_rows.rows(), " tracks");
  for (Eigen::Index n = 0; n < past_rows.rows(); ++n)
    CheckOutput((*out)[static_cast<std::size_t>(n)], layout_);
  for (Eigen::Index n = 0; n < past_rows.rows(); ++n) {
    for (int i = 0; i < observed_; ++i) {
      ws->past(i, 0) = past_rows(n, 2 * i);
      ws->past(i, 1) = past_rows(n, 2 * i + 1);
    }
    Predict(ws->past, ws, &(*out)[static_cast<std::size_t>(n)]);
  }
}

}  // namespace foresight::span
