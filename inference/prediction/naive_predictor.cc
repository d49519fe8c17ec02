#include "inference/prediction/naive_predictor.h"

#include <cmath>

#include "core/ego_frame.h"
#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight {

NaivePredictor NaivePredictor::Load(const std::string& path) {
  const Artifact art = Artifact::Open(path, kNaiveModelType);
  const h5::File& f = art.file();
  NaivePredictor p;
  p.observed_ = art.IntAttr("/model", "observed", 2, 100000);
  p.predicted_ = art.IntAttr("/model", "predicted", 1, 100000);
  p.seconds_per_step_ = art.DoubleAttr("/model", "seconds_per_step", 1e-6, 3600);
  p.rotate_ = art.IntAttr("/model", "rotate_to_heading", 0, 1) != 0;
  const int in = 2 * p.observed_;
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
  p.mlp_ = Mlp::LoadListed(f, "/model", "dense_layers", "/weights/");
  FS_THROW_UNLESS(p.mlp_.input_size() == in, path, ": network takes ", p.mlp_.input_size(),
                  " inputs, expected 2 x observed = ", in);
  FS_THROW_UNLESS(p.mlp_.output_size() == 2 * p.predicted_, path, ": network gives ",
                  p.mlp_.output_size(), " outputs, expected 2 x predicted = ", 2 * p.predicted_);
  return p;
}

void NaivePredictor::Save(const std::string& path, const NaivePredictorWeights& w,
                          const std::string& config_yaml, std::int64_t seed) {
  FS_THROW_UNLESS(!w.layer_names.empty() && w.layer_names.size() == w.mlp.layers().size(), path,
                  ": ", w.layer_names.size(), " layer names for ", w.mlp.layers().size(),
                  " dense layers");
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kNaiveModelType, config_yaml, seed);
    f->SetAttr("/model", "observed", static_cast<std::int64_t>(w.observed));
    f->SetAttr("/model", "predicted", static_cast<std::int64_t>(w.predicted));
    f->SetAttr("/model", "seconds_per_step", w.seconds_per_step);
    f->SetAttr("/model", "rotate_to_heading", static_cast<std::int64_t>(w.rotate_to_heading));
    f->WriteMatrix("/normalisation/input_mean", w.input_mean);
    f->WriteMatrix("/normalisation/input_std", w.input_std);
    w.mlp.SaveListed(f, "/model", "dense_layers", "/weights/", w.layer_names);
  });
}

NaivePredictor::Workspace NaivePredictor::MakeWorkspace() const {
  return {Eigen::VectorXf::Zero(2 * observed_), mlp_.MakeWorkspace()};
}

void NaivePredictor::Predict(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 2>>& past,
                             Workspace* ws,
                             Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 2>> future) const {
  FS_THROW_UNLESS(past.rows() == observed_, "NaivePredictor: expected ", observed_,
                  " observed points, got ", past.rows());
  FS_THROW_UNLESS(future.rows() == predicted_, "NaivePredictor: the output holds ", future.rows(),
                  " points, the model predicts ", predicted_);
  FS_THROW_UNLESS(past.allFinite(), "NaivePredictor: observed track contains NaN or inf");
  const EgoFrame frame = EgoFrame::FromPast(
      observed_, [&](int i) { return Eigen::Vector2d(past(i, 0), past(i, 1)); }, rotate_);
  for (int i = 0; i < observed_; ++i) {
    const Eigen::Vector2d q = frame.ToEgo(Eigen::Vector2d(past(i, 0), past(i, 1)));
    ws->input[2 * i] = static_cast<float>((q.x() - input_mean_[2 * i]) / input_std_[2 * i]);
    ws->input[2 * i + 1] =
        static_cast<float>((q.y() - input_mean_[2 * i + 1]) / input_std_[2 * i + 1]);
  }
  const auto out = mlp_.Forward(ws->input, &ws->mlp);
  for (int k = 0; k < predicted_; ++k) {
    const Eigen::Vector2d ego(out[2 * k], out[2 * k + 1]);
    future.row(k) = frame.ToWorld(ego).transpose();
  }
}

}  // namespace foresight
