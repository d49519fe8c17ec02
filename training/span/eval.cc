#include "training/span/eval.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/ego_frame.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/json.h"
#include "core/log.h"
#include "core/matrix_normal.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"
#include "training/span/plots.h"

namespace foresight::span {
namespace fs = std::filesystem;

namespace {

EgoFrame FrameOfWindow(const WindowSet& w, int n) {
  return EgoFrame::FromPast(
      w.observed, [&](int i) { return w.Past(n, i); }, true);
}

/// Constant velocity from the last observed step, with a Gaussian per horizon fitted on training
/// windows in the ego frame (x along the observed heading).
struct ConstantVelocity {
  std::vector<Eigen::Matrix2d> cov_ego;  // [f]

  static ConstantVelocity Fit(const WindowSet& train) {
    ConstantVelocity cv;
    const int f = train.predicted, p = train.observed;
    FS_THROW_UNLESS(train.size() > 0, "constant-velocity baseline: no training windows of ", p + f,
                    " points to fit its Gaussian to");
    cv.cov_ego.assign(static_cast<std::size_t>(f), Eigen::Matrix2d::Zero());
    for (int n = 0; n < train.size(); ++n) {
      const EgoFrame frame = FrameOfWindow(train, n);
      const Eigen::Vector2d v = train.Past(n, p - 1) - train.Past(n, p - 2);
      for (int k = 0; k < f; ++k) {
        const Eigen::Vector2d r = frame.rotation.transpose() *
                                  (train.Future(n, k) - (train.Past(n, p - 1) + (k + 1) * v));
        cv.cov_ego[static_cast<std::size_t>(k)] += r * r.transpose();
      }
    }
    for (auto& c : cv.cov_ego) {
      c /= train.size();
      c += 1e-6 * Eigen::Matrix2d::Identity();
    }
    return cv;
  }
  Eigen::Vector2d Mean(const WindowSet& w, int n, int k) const {
    const int p = w.observed;
    return w.Past(n, p - 1) + (k + 1) * (w.Past(n, p - 1) - w.Past(n, p - 2));
  }
};

double Ade(const Eigen::Matrix<double, Eigen::Dynamic, 2>& path, const WindowSet& w, int n) {
  double s = 0;
  for (int k = 0; k < w.predicted; ++k) s += (path.row(k).transpose() - w.Future(n, k)).norm();
  return s / w.predicted;
}
double Fde(const Eigen::Matrix<double, Eigen::Dynamic, 2>& path, const WindowSet& w, int n) {
  return (path.row(w.predicted - 1).transpose() - w.Future(n, w.predicted - 1)).norm();
}

/// The test split is held out only when the tracks, windows and seed are the training run's: the
/// data, windows and seed sections of `config` must equal those stored in the artifact's /config
/// (data.root, where the files are, may differ).
void CheckSameDataAsTraining(const ExperimentConfig& config, const std::string& artifact) {
  const ExperimentConfig trained = config::ExperimentConfigFromYaml<ExperimentConfig>(
      Artifact::Open(artifact, kModelType).config_yaml(), artifact + ":/config");
  const auto tree = [](ExperimentConfig c) {
    c.data.root.clear();
    return config::ParseYaml(config::ToYaml(c), "resolved config");
  };
  const YAML::Node t = tree(trained), g = tree(config);
  for (const char* section : {"data", "windows", "seed"}) {
    const std::string d = config::FirstDifference(t[section], g[section], section);
    FS_THROW_UNLESS(d.empty(), artifact, ": the model was trained with ", d,
                    " as given; evaluate with the run's config.yaml (the data, windows and seed "
                    "sections must match training, or the test split is not held out)");
  }
}

}  // namespace

std::string EvalReport::ToJson(int num_samples) const {
  JsonObject j;
  j.Set("windows", windows).Set("num_samples", num_samples);
  j.Set("covariance_scale", covariance_scale);
  j.Set("ade", model.ade).Set("fde", model.fde).Set("nll", model.nll);
  j.Set("best_of_20_ade", model.best_of_n_ade).Set("best_of_20_fde", model.best_of_n_fde);
  j.Set("cv_ade", cv.ade).Set("cv_fde", cv.fde).Set("cv_nll", cv.nll);
  j.Set("cv_best_of_20_ade", cv.best_of_n_ade).Set("cv_best_of_20_fde", cv.best_of_n_fde);
  const auto calibration = [&](const Metrics& m, const Metrics& c) {
    JsonObject o;
    o.Set("horizon_s", horizon_s)
        .Set("nominal_1sigma", 1 - std::exp(-0.5))
        .Set("nominal_2sigma", 1 - std::exp(-2.0));
    o.Set("within_1sigma", m.within_1sigma).Set("within_2sigma", m.within_2sigma);
    o.Set("cv_within_1sigma", c.within_1sigma).Set("cv_within_2sigma", c.within_2sigma);
    return o;
  };
  j.Set("calibration", calibration(model, cv));
  if (val_windows > 0) {
    JsonObject v;
    v.Set("windows", val_windows);
    v.Set("ade", val_model.ade).Set("fde", val_model.fde).Set("nll", val_model.nll);
    v.Set("cv_ade", val_cv.ade).Set("cv_fde", val_cv.fde).Set("cv_nll", val_cv.nll);
    v.Set("calibration", calibration(val_model, val_cv));
    j.Set("val", v);
  } else {
    j.Set("val", std::nan(""));  // null: no validation windows
  }
  return j.Dump() + "\n";
}

EvalReport EvaluateOn(const std::string& artifact, const WindowSet& train, const WindowSet& test,
                      const EvalConfig& ec) {
  const Predictor model = Predictor::Load(artifact);
  FS_THROW_UNLESS(model.observed() == test.observed, artifact, ": model observes ",
                  model.observed(), " points but the test windows have ", test.observed);
  FS_THROW_UNLESS(std::abs(model.seconds_per_step() - test.seconds_per_step) < 1e-9, artifact,
                  ": model was trained at ", model.seconds_per_step(), " s per step, data has ",
                  test.seconds_per_step);
  FS_THROW_UNLESS(test.size() > 0, artifact, ": no windows to evaluate on");
  const ConstantVelocity cv = ConstantVelocity::Fit(train);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  const int f = test.predicted, N = ec.num_samples;
  const int count = ec.max_windows > 0 ? std::min(ec.max_windows, test.size()) : test.size();
  Eigen::VectorXd times(f);
  for (int k = 0; k < f; ++k) times[k] = (k + 1) * test.seconds_per_step;
  std::mt19937_64 rng(static_cast<std::uint64_t>(ec.sample_seed));
  std::normal_distribution<double> n01;
  std::vector<Eigen::Matrix2d> cv_chol(static_cast<std::size_t>(f));
  for (int k = 0; k < f; ++k)
    cv_chol[static_cast<std::size_t>(k)] = cv.cov_ego[static_cast<std::size_t>(k)].llt().matrixL();

  EvalReport rep;
  rep.windows = count;
  rep.covariance_scale = model.covariance_scale();
  rep.horizon_s.assign(times.data(), times.data() + f);
  for (Metrics* m : {&rep.model, &rep.cv}) {
    m->within_1sigma.assign(static_cast<std::size_t>(f), 0.0);
    m->within_2sigma.assign(static_cast<std::size_t>(f), 0.0);
  }
  // Counts a true position inside the 1- and 2-sigma ellipses of N(mean, cov) at step k.
  const auto count_inside = [](Metrics* m, int k, const Eigen::Vector2d& x,
                               const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov) {
    const double d2 = SquaredMahalanobis2(x, mean, cov);
    m->within_1sigma[static_cast<std::size_t>(k)] += d2 <= 1.0;
    m->within_2sigma[static_cast<std::size_t>(k)] += d2 <= 4.0;
  };
  Eigen::Vector2d mix_mean;
  Eigen::Matrix2d mix_cov;
  Eigen::Matrix<double, Eigen::Dynamic, 2> path(f, 2), cv_path(f, 2);
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(test.observed, 2);
  for (int n = 0; n < count; ++n) {
    for (int i = 0; i < test.observed; ++i) past.row(i) = test.Past(n, i).transpose();
    model.Predict(past, &ws, &dist);
    const EgoFrame frame = FrameOfWindow(test, n);
    double nll = 0, cv_nll = 0;
    for (int k = 0; k < f; ++k) {
      path.row(k) = dist.MeanPosition(times[k]).transpose();
      cv_path.row(k) = cv.Mean(test, n, k).transpose();
      nll -= dist.LogDensity(times[k], test.Future(n, k));
      const Eigen::Matrix2d cov =
          frame.rotation * cv.cov_ego[static_cast<std::size_t>(k)] * frame.rotation.transpose();
      cv_nll -= LogGaussian2(test.Future(n, k), cv.Mean(test, n, k), cov);
      dist.MixturePosition(times[k], &mix_mean, &mix_cov);
      count_inside(&rep.model, k, test.Future(n, k), mix_mean, mix_cov);
      count_inside(&rep.cv, k, test.Future(n, k), cv.Mean(test, n, k), cov);
    }
    rep.model.ade += Ade(path, test, n);
    rep.model.fde += Fde(path, test, n);
    rep.model.nll += nll / f;
    rep.cv.ade += Ade(cv_path, test, n);
    rep.cv.fde += Fde(cv_path, test, n);
    rep.cv.nll += cv_nll / f;
    double best_ade = INFINITY, best_fde = INFINITY, cv_best_ade = INFINITY, cv_best_fde = INFINITY;
    for (int s = 0; s < N; ++s) {
      dist.SamplePath(times, &rng, path);
      best_ade = std::min(best_ade, Ade(path, test, n));
      best_fde = std::min(best_fde, Fde(path, test, n));
      const Eigen::Vector2d z(n01(rng), n01(rng));  // one draw per path: correlated over horizons
      for (int k = 0; k < f; ++k)
        cv_path.row(k) =
            (cv.Mean(test, n, k) + frame.rotation * (cv_chol[static_cast<std::size_t>(k)] * z))
                .transpose();
      cv_best_ade = std::min(cv_best_ade, Ade(cv_path, test, n));
      cv_best_fde = std::min(cv_best_fde, Fde(cv_path, test, n));
    }
    rep.model.best_of_n_ade += best_ade;
    rep.model.best_of_n_fde += best_fde;
    rep.cv.best_of_n_ade += cv_best_ade;
    rep.cv.best_of_n_fde += cv_best_fde;
  }
  for (Metrics* m : {&rep.model, &rep.cv}) {
    const double d = count;
    m->ade /= d, m->fde /= d, m->nll /= d, m->best_of_n_ade /= d, m->best_of_n_fde /= d;
    for (double& share : m->within_1sigma) share /= d;
    for (double& share : m->within_2sigma) share /= d;
  }
  return rep;
}

EvalReport Evaluate(const ExperimentConfig& c, const std::string& artifact,
                    const std::string& out_dir) {
  CheckSameDataAsTraining(c, artifact);
  const TrackSplit split = LoadPedestrianSplits(c.data, static_cast<std::uint64_t>(c.seed));
  const WindowSet train = MakeWindows(split.train, c.windows);
  const WindowSet test = MakeWindows(split.test, c.windows);
  const int length = c.windows.observed + c.windows.predicted;
  FS_THROW_UNLESS(test.size() > 0, "no test windows: no test track has windows.observed + ",
                  "windows.predicted = ", length, " points (",
                  c.data.test_files.empty() ? "raise data.test_fraction" : "check data.test_files",
                  ")");
  FS_THROW_UNLESS(train.size() > 0, "no training windows for the constant-velocity baseline: no ",
                  "training track has windows.observed + windows.predicted = ", length,
                  " points (data.train_files, data.val_fraction, data.test_fraction)");
  EvalReport rep = EvaluateOn(artifact, train, test, c.eval);
  const WindowSet val = MakeWindows(split.val, c.windows);
  if (val.size() > 0) {
    const EvalReport v = EvaluateOn(artifact, train, val, c.eval);
    rep.val_windows = v.windows;
    rep.val_model = v.model;
    rep.val_cv = v.cv;
  }
  fs::create_directories(out_dir + "/plots");
  WriteFileAtomically(out_dir + "/eval.json", rep.ToJson(c.eval.num_samples));
  if (c.eval.plot_tracks > 0) PlotSamples(artifact, test, c.eval, out_dir + "/plots/samples.png");
  log::Info("eval on ", rep.windows, " windows: ADE ", rep.model.ade, " FDE ", rep.model.fde,
            " NLL ", rep.model.nll, " best-of-", c.eval.num_samples, " ", rep.model.best_of_n_ade,
            "/", rep.model.best_of_n_fde, " | CV ADE ", rep.cv.ade, " FDE ", rep.cv.fde, " NLL ",
            rep.cv.nll);
  return rep;
}

}  // namespace foresight::span
