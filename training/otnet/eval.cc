#include "training/otnet/eval.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <map>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "training/otnet/plots.h"
#include "training/otnet/transfer.h"

namespace foresight::otnet {
namespace fs = std::filesystem;

namespace {

double PointToSet(const Eigen::RowVector2d& p, const Eigen::MatrixX2d& set) {
  return std::sqrt((set.rowwise() - p).rowwise().squaredNorm().minCoeff());
}

double LowerBound(const Eigen::MatrixX2d& g, const Eigen::MatrixX2d& t, TrajectoryDistance d) {
  const Eigen::Index gn = g.rows() - 1, tn = t.rows() - 1;
  if (d == TrajectoryDistance::kFrechet)
    return std::max((g.row(0) - t.row(0)).norm(), (g.row(gn) - t.row(tn)).norm());
  return std::max(std::max(PointToSet(g.row(0), t), PointToSet(g.row(gn), t)),
                  std::max(PointToSet(t.row(0), g), PointToSet(t.row(tn), g)));
}

double Distance(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b, TrajectoryDistance d) {
  return d == TrajectoryDistance::kFrechet ? TrajectoryFrechet(a, b) : TrajectoryHausdorff(a, b);
}

/// Means of named figures in first-seen order.
class Accumulator {
 public:
  void Add(const std::string& key, double v) {
    if (!sums_.count(key)) order_.push_back(key);
    auto& s = sums_[key];
    s.first += v;
    s.second += 1;
  }
  Scores Means(const std::string& prefix) const {
    Scores out;
    for (const std::string& k : order_) {
      const auto& s = sums_.at(k);
      out.emplace_back(prefix + k, s.first / s.second);
    }
    return out;
  }

 private:
  std::vector<std::string> order_;
  std::map<std::string, std::pair<double, int>> sums_;
};

std::vector<Eigen::MatrixX2d> Resampled(const std::vector<Eigen::MatrixX2d>& trajectories,
                                        int points) {
  std::vector<Eigen::MatrixX2d> out;
  out.reserve(trajectories.size());
  for (const Eigen::MatrixX2d& t : trajectories) out.push_back(ResampleUniform(t, points));
  return out;
}

double MeanMtd(const std::vector<Eigen::MatrixX2d>& generated,
               const std::vector<Eigen::MatrixX2d>& truth, TrajectoryDistance d) {
  double s = 0;
  for (const Eigen::MatrixX2d& g : generated) s += MinimumDistance(g, truth, d);
  return s / static_cast<double>(generated.size());
}

double MeanAnll(const PerTimeDensity& density, const std::vector<Eigen::MatrixX2d>& truth) {
  double s = 0;
  for (const Eigen::MatrixX2d& t : truth) s += AverageNegativeLogLikelihood(density, t);
  return s / static_cast<double>(truth.size());
}

/// The mean trajectory over every training trajectory and its per-time Gaussian (streamed: the
/// training set may hold tens of thousands of trajectories).
struct MeanBaseline {
  Eigen::MatrixX2d mean;
  PerTimeDensity density;
};

MeanBaseline FitMeanBaseline(const OtnetSplit& train, int points, double floor) {
  Eigen::MatrixX2d sum = Eigen::MatrixX2d::Zero(points, 2);
  Eigen::MatrixXd second = Eigen::MatrixXd::Zero(points, 3);  // xx, xy, yy
  long n = 0;
  for (const MapTrajectories& m : train.maps)
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      const Eigen::MatrixX2d r = ResampleUniform(t, points);
      sum += r;
      second.col(0) += r.col(0).cwiseProduct(r.col(0));
      second.col(1) += r.col(0).cwiseProduct(r.col(1));
      second.col(2) += r.col(1).cwiseProduct(r.col(1));
      ++n;
    }
  FS_THROW_UNLESS(n > 0, "otnet eval: no training trajectories for the mean baseline");
  MeanBaseline b;
  b.mean = sum / static_cast<double>(n);
  Eigen::MatrixXd cov(points, 3);
  cov.col(0) = second.col(0) / n - b.mean.col(0).cwiseProduct(b.mean.col(0));
  cov.col(1) = second.col(1) / n - b.mean.col(0).cwiseProduct(b.mean.col(1));
  cov.col(2) = second.col(2) / n - b.mean.col(1).cwiseProduct(b.mean.col(1));
  cov.col(0).array() += floor;
  cov.col(2).array() += floor;
  b.density.weights = Eigen::VectorXd::Ones(1);
  b.density.means = {b.mean};
  b.density.covs = {cov};
  return b;
}

std::uint64_t MapSeed(std::int64_t seed, std::size_t index, std::uint64_t salt) {
  return static_cast<std::uint64_t>(seed) * 0x9E3779B97F4A7C15ull +
         (index + 1) * 0xBF58476D1CE4E5B9ull + salt;
}

}  // namespace

Eigen::Vector2d NearestFreeCentre(const BinaryGrid& g, const Eigen::Vector2d& p) {
  if (!g.OccupiedAt(p.x(), p.y())) return p;
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector2d out = p;
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c)
      if (!g.at(r, c)) {
        const Eigen::Vector2d q(c + 0.5, r + 0.5);
        const double d = (q - p).squaredNorm();
        if (d < best) {
          best = d;
          out = q;
        }
      }
  FS_THROW_UNLESS(std::isfinite(best), "otnet eval: the map has no free cell");
  return out;
}

double MinimumDistance(const Eigen::MatrixX2d& generated,
                       const std::vector<Eigen::MatrixX2d>& truth, TrajectoryDistance d) {
  FS_THROW_UNLESS(!truth.empty() && generated.rows() > 0,
                  "MinimumDistance: empty trajectory or ground truth");
  std::vector<std::pair<double, std::size_t>> bounds(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    bounds[i] = {LowerBound(generated, truth[i], d), i};
  std::sort(bounds.begin(), bounds.end());
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [bound, i] : bounds) {
    if (bound >= best) break;
    best = std::min(best, Distance(generated, truth[i], d));
  }
  return best;
}

Scores ScoreSplit(const ExperimentConfig& c, const OtnetModel& model, const OtnetSplit& train,
                  const OtnetSplit& split, const std::string& prefix, const std::string& plot_png) {
  const int points = c.eval.points;
  const Eigen::VectorXd taus = UniformTaus(points);
  // k-NN over every training map (not only the representative database).
  std::vector<BinaryGrid> train_maps;
  for (const MapTrajectories& m : train.maps) train_maps.push_back(m.map);
  const MapEncoder knn(train_maps, c.otnet.length_scale);
  MapEncoder::Workspace knn_ws = knn.MakeWorkspace();
  const MeanBaseline mean = FitMeanBaseline(train, points, c.eval.variance_floor);
  const std::vector<Eigen::MatrixX2d> mean_set{mean.mean};

  OtnetModel::Workspace ws = model.MakeWorkspace(c.eval.generated, points);
  GenerateOptions gen;
  gen.count = c.eval.generated;
  gen.points = points;
  gen.max_attempts = std::max(c.eval.max_attempts, c.eval.generated);
  gen.check_step = c.eval.check_step;

  Accumulator acc;
  long accepted = 0, attempts = 0, rejected = 0, cond_accepted = 0, cond_attempts = 0;
  int maps_without_valid = 0, cond_maps_without_valid = 0, maps_scored = 0;
  std::vector<TrajectoryPanel> row_otnet, row_knn, row_cond;
  for (std::size_t mi = 0; mi < split.maps.size(); ++mi) {
    const MapTrajectories& m = split.maps[mi];
    if (m.trajectories.empty()) continue;  // counted: maps - maps_scored
    ++maps_scored;
    const std::vector<Eigen::MatrixX2d> truth = Resampled(m.trajectories, points);

    // OTNet.
    const Mixture& mixture = model.Predict(m.map, &ws);
    std::mt19937_64 rng(MapSeed(c.seed, mi, 1));
    GenerateStats st = model.Generate(m.map, mixture, gen, &rng, &ws);
    accepted += st.accepted;
    attempts += st.attempts;
    rejected += st.rejected;
    if (st.accepted == 0) {
      // Nothing collision-free within max_attempts: score the raw samples (counted).
      ++maps_without_valid;
      GenerateOptions raw = gen;
      raw.reject_collisions = false;
      st = model.Generate(m.map, mixture, raw, &rng, &ws);
    }
    const std::vector<Eigen::MatrixX2d> generated(ws.generated.begin(),
                                                  ws.generated.begin() + st.accepted);
    acc.Add("hausdorff", MeanMtd(generated, truth, TrajectoryDistance::kHausdorff));
    acc.Add("frechet", MeanMtd(generated, truth, TrajectoryDistance::kFrechet));
    acc.Add("anll", MeanAnll(model.Density(mixture, taus), truth));
    acc.Add("coverage_hausdorff", MeanMtd(truth, generated, TrajectoryDistance::kHausdorff));
    // Control: OTNet's own samples scored as the baselines are (one Gaussian per tau), so that the
    // ANLL comparison can be read without the advantage of the mixture.
    acc.Add("samples_anll", MeanAnll(FitPerTimeGaussian(generated, c.eval.variance_floor), truth));

    // k-NN: the nearest training map's trajectories.
    const int nearest = knn.Nearest(m.map, &knn_ws);
    const std::vector<Eigen::MatrixX2d> transferred =
        Resampled(train.maps[nearest].trajectories, points);
    acc.Add("knn_hausdorff", MeanMtd(transferred, truth, TrajectoryDistance::kHausdorff));
    acc.Add("knn_frechet", MeanMtd(transferred, truth, TrajectoryDistance::kFrechet));
    acc.Add("knn_anll", MeanAnll(FitPerTimeGaussian(transferred, c.eval.variance_floor), truth));
    // Coverage improves with the number of trajectories: score as many as OTNet generates
    // (evenly spaced in the nearest map's file order).
    std::vector<Eigen::MatrixX2d> knn_subset;
    const std::size_t n_knn = std::min(transferred.size(), static_cast<std::size_t>(gen.count));
    for (std::size_t i = 0; i < n_knn; ++i)
      knn_subset.push_back(transferred[i * transferred.size() / n_knn]);
    acc.Add("knn_coverage_hausdorff", MeanMtd(truth, knn_subset, TrajectoryDistance::kHausdorff));

    // The mean training trajectory.
    acc.Add("mean_hausdorff", MeanMtd(mean_set, truth, TrajectoryDistance::kHausdorff));
    acc.Add("mean_frechet", MeanMtd(mean_set, truth, TrajectoryDistance::kFrechet));
    acc.Add("mean_anll", MeanAnll(mean.density, truth));
    acc.Add("mean_coverage_hausdorff", MeanMtd(truth, mean_set, TrajectoryDistance::kHausdorff));

    // Conditioned on the map's mean ground-truth start.
    Eigen::Vector2d start = Eigen::Vector2d::Zero();
    std::vector<Eigen::MatrixX2d> conditioned, shifted;
    if (c.eval.conditioned) {
      for (const Eigen::MatrixX2d& t : m.trajectories) start += t.row(0).transpose();
      start = NearestFreeCentre(m.map, start / static_cast<double>(m.trajectories.size()));
      model.ConditionOnStart(mixture, start, ComponentSelection::kAll, &ws.conditioned);
      std::mt19937_64 crng(MapSeed(c.seed, mi, 2));
      GenerateStats cs = model.Generate(m.map, ws.conditioned, gen, &crng, &ws);
      cond_accepted += cs.accepted;
      cond_attempts += cs.attempts;
      if (cs.accepted == 0) {
        ++cond_maps_without_valid;
        GenerateOptions raw = gen;
        raw.reject_collisions = false;
        cs = model.Generate(m.map, ws.conditioned, raw, &crng, &ws);
      }
      conditioned.assign(ws.generated.begin(), ws.generated.begin() + cs.accepted);
      for (const Eigen::MatrixX2d& t : transferred)
        shifted.push_back(t.rowwise() + (start.transpose() - t.row(0)));
      acc.Add("cond_hausdorff", MeanMtd(conditioned, truth, TrajectoryDistance::kHausdorff));
      acc.Add("cond_frechet", MeanMtd(conditioned, truth, TrajectoryDistance::kFrechet));
      acc.Add("knn_cond_hausdorff", MeanMtd(shifted, truth, TrajectoryDistance::kHausdorff));
      acc.Add("knn_cond_frechet", MeanMtd(shifted, truth, TrajectoryDistance::kFrechet));
    }

    if (!plot_png.empty() && static_cast<int>(row_otnet.size()) < c.eval.plot_maps) {
      const auto head = [](const std::vector<Eigen::MatrixX2d>& v, std::size_t n) {
        return std::vector<Eigen::MatrixX2d>(v.begin(), v.begin() + std::min(n, v.size()));
      };
      TrajectoryPanel p;
      p.map = &m.map;
      p.truth = head(truth, 60);
      p.generated = head(generated, 30);
      p.title = m.id + ": OTNet (red), truth (blue)";
      row_otnet.push_back(p);
      p.generated = head(transferred, 30);
      p.title = "k-NN: " + train.maps[nearest].id;
      row_knn.push_back(p);
      if (c.eval.conditioned) {
        p.generated = head(conditioned, 30);
        p.has_start = true;
        p.start = start;
        p.title = "OTNet from the mean start";
        row_cond.push_back(p);
      }
    }
  }
  Scores out = acc.Means(prefix);
  out.emplace_back(prefix + "acceptance_rate",
                   attempts ? static_cast<double>(accepted) / attempts : 0.0);
  out.emplace_back(prefix + "rejected_samples", static_cast<double>(rejected));
  out.emplace_back(prefix + "maps_without_valid_samples", maps_without_valid);
  if (c.eval.conditioned) {
    out.emplace_back(prefix + "cond_acceptance_rate",
                     cond_attempts ? static_cast<double>(cond_accepted) / cond_attempts : 0.0);
    out.emplace_back(prefix + "cond_maps_without_valid_samples", cond_maps_without_valid);
  }
  out.emplace_back(prefix + "maps", static_cast<double>(split.maps.size()));
  out.emplace_back(prefix + "maps_scored", maps_scored);
  out.emplace_back(prefix + "trajectories", split.trajectories());
  if (maps_scored < static_cast<int>(split.maps.size()))
    log::Warn("otnet eval: ", prefix.empty() ? "test" : prefix, ": ",
              static_cast<int>(split.maps.size()) - maps_scored,
              " map(s) without trajectories were not scored");
  if (maps_without_valid + cond_maps_without_valid > 0)
    log::Warn("otnet eval: ", prefix.empty() ? "test" : prefix, ": ", maps_without_valid,
              " map(s) (", cond_maps_without_valid,
              " start-conditioned) had no collision-free "
              "sample in ",
              gen.max_attempts, " attempts; their raw samples were scored");
  if (!plot_png.empty() && !row_otnet.empty()) {
    std::vector<std::vector<TrajectoryPanel>> rows{row_otnet, row_knn};
    if (!row_cond.empty()) rows.push_back(row_cond);
    DrawTrajectoryPanels(rows, plot_png);
  }
  return out;
}

std::string EvaluateOtnet(const ExperimentConfig& c, const OtnetData& d,
                          const std::string& artifact, const std::string& plot_dir) {
  const OtnetModel model = OtnetModel::Load(artifact);
  FS_THROW_UNLESS(model.basis().size() == c.otnet.basis, artifact, ": basis ", model.basis().size(),
                  " differs from the config's otnet.basis ", c.otnet.basis);
  if (!plot_dir.empty()) fs::create_directories(plot_dir);
  Scores scores;
  log::Info("otnet eval: validation maps");
  for (auto& s : ScoreSplit(c, model, d.train, d.val, "val_", "")) scores.push_back(s);
  log::Info("otnet eval: test maps");
  for (auto& s : ScoreSplit(c, model, d.train, d.test, "",
                            plot_dir.empty() ? "" : plot_dir + "/test_maps.png"))
    scores.push_back(s);
  if (!c.transfer.occupancy_artifact.empty())
    for (auto& s : TransferToOccupancyMap(c, model, d.train,
                                          plot_dir.empty() ? "" : plot_dir + "/transfer.png"))
      scores.push_back(s);
  std::ostringstream o;
  o << std::setprecision(6) << "{\n";
  for (std::size_t i = 0; i < scores.size(); ++i) {
    o << "  \"" << scores[i].first << "\": ";
    if (std::isfinite(scores[i].second))
      o << scores[i].second;
    else
      o << "null";
    o << (i + 1 < scores.size() ? ",\n" : "\n");
  }
  o << "}\n";
  for (const auto& [k, v] : scores)
    if (k == "hausdorff" || k == "frechet" || k == "anll" || k == "knn_hausdorff" ||
        k == "knn_frechet" || k == "knn_anll")
      log::Info("otnet eval: ", k, " ", v);
  return o.str();
}

}  // namespace foresight::otnet
