#include "training/constrained/eval.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/json.h"
#include "core/log.h"
#include "inference/constrained/distribution_projector.h"
#include "inference/constrained/prediction_metrics.h"
#include "inference/mapping/occupancy_map.h"
#include "inference/prediction/naive_predictor.h"
#include "inference/prediction/span_predictor.h"
#include "models/occupancy/raster_map.h"
#include "training/constrained/plots.h"

namespace foresight::constrained {
namespace fs = std::filesystem;

RunArtifacts ArtifactsOf(const ExperimentConfig& c, const std::string& run_dir) {
  RunArtifacts a;
  a.prior = run_dir + "/prior.h5";
  if (c.ktm.enabled) a.ktm = run_dir + "/ktm.h5";
  if (c.naive.enabled) a.naive = run_dir + "/naive.h5";
  a.maps_dir = run_dir;
  return a;
}

bool FitSceneMaps(const ExperimentConfig& c, const std::vector<MapScene>& scenes,
                  const std::string& run_dir, const std::atomic<bool>* interrupt) {
  fs::create_directories(run_dir + "/maps");
  for (const MapScene& s : scenes) {
    if (interrupt && interrupt->load()) return false;
    const std::string path = run_dir + "/" + SceneMapFile(s);
    if (fs::exists(path)) continue;
    const auto t0 = std::chrono::steady_clock::now();
    occupancy::WriteRasterMap(s.raster, c.map.Options(), path, config::ToYaml(c), c.seed);
    log::Info("constrained: fitted the map of ", s.name, " (",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
              " s) -> ", path);
  }
  return true;
}

namespace {

/// Means of the scores of a set of windows.
struct Block {
  int n = 0, violating = 0, violating_converged = 0;
  double ade_n = 0, fde_n = 0, ade_m = 0, fde_m = 0, al = 0, anll = 0;
  bool has_cost = false, has_converged = false;

  void Add(const PredictionScores& s) {
    ++n;
    ade_n += s.ade_nearest;
    fde_n += s.fde_nearest;
    ade_m += s.ade_mixture;
    fde_m += s.fde_mixture;
    al += s.al;
    anll += s.anll;
  }
  void AddCost(double cost, double epsilon) {
    has_cost = true;
    violating += !(cost <= epsilon);  // a cost that could not be computed (NaN) is not compliant
  }
  /// C under the converged quadrature (what the table's compliance is also judged by).
  void AddConvergedCost(double cost, double epsilon) {
    has_converged = true;
    violating_converged += !(cost <= epsilon);
  }
  JsonObject Json() const {
    const double k = n > 0 ? 1.0 / n : NAN;
    JsonObject o;
    o.Set("windows", n);
    o.Set("ade", ade_n * k).Set("fde", fde_n * k);
    o.Set("ade_mixture_mean", ade_m * k).Set("fde_mixture_mean", fde_m * k);
    o.Set("al", al * k).Set("anll", anll * k);
    if (has_cost) o.Set("cvp", violating * k).Set("violating", violating);
    if (has_converged) {
      o.Set("cvp_converged", violating_converged * k);
      o.Set("violating_converged", violating_converged);
    }
    return o;
  }
};

JsonObject Percentiles(const std::vector<double>& v, double scale) {
  JsonObject o;
  o.Set("count", static_cast<int>(v.size()));
  o.Set("median", Percentile(v, 50) * scale).Set("p90", Percentile(v, 90) * scale);
  o.Set("p99", Percentile(v, 99) * scale).Set("max", Percentile(v, 100) * scale);
  return o;
}

/// Monte Carlo estimate of the mixture's C on `map` (rectangle rule over `times`, as the cost):
/// independent of the quadrature code (positions from TrajectoryDistribution::Position).
std::pair<double, double> MonteCarloCost(const TrajectoryDistribution& d,
                                         const Eigen::VectorXd& times, const occupancy::Map& map,
                                         int samples, std::mt19937_64* rng) {
  occupancy::MapWorkspace ws = map.MakeWorkspace();
  std::normal_distribution<double> normal;
  const int per_time = std::max(50, samples / static_cast<int>(times.size()));
  double c = 0, var = 0;
  const double k = 1.0 / static_cast<double>(times.size());
  for (int r = 0; r < d.components(); ++r)
    for (Eigen::Index t = 0; t < times.size(); ++t) {
      Eigen::Vector2d mu;
      Eigen::Matrix2d cov;
      d.Position(times[t], r, &mu, &cov);
      const Eigen::Matrix2d l = Eigen::LLT<Eigen::Matrix2d>(cov).matrixL();
      double sum = 0, sum2 = 0;
      for (int s = 0; s < per_time; ++s) {
        const Eigen::Vector2d x = mu + l * Eigen::Vector2d(normal(*rng), normal(*rng));
        const double p = map.Probability(x.x(), x.y(), &ws);
        sum += p;
        sum2 += p * p;
      }
      const double mean = sum / per_time;
      const double v = std::max(0.0, sum2 / per_time - mean * mean) / per_time;
      c += d.alpha(r) * k * mean;
      var += d.alpha(r) * d.alpha(r) * k * k * v;
    }
  return {c, std::sqrt(var)};
}

/// Monte Carlo estimate of the mixture's C = 1/T int_0^T E[p(m=1|x(t))] dt itself, with no time
/// grid: t stratified over [0, horizon) (samples / strata uniform draws in each of `strata` equal
/// intervals), x ~
/// N(mu_r(t), Sigma_r(t)) from TrajectoryDistribution::Position. What every quadrature of C is
/// judged against (independent of the cost code and of its time points). {estimate, standard
/// error}.
std::pair<double, double> ContinuousMonteCarloCost(const TrajectoryDistribution& d, double horizon,
                                                   const occupancy::Map& map, int samples,
                                                   int strata, std::mt19937_64* rng) {
  occupancy::MapWorkspace ws = map.MakeWorkspace();
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unit;
  const int per_stratum = std::max(2, samples / strata);
  double c = 0, var = 0;
  for (int r = 0; r < d.components(); ++r) {
    double mean_r = 0, var_r = 0;
    for (int j = 0; j < strata; ++j) {
      double sum = 0, sum2 = 0;
      for (int s = 0; s < per_stratum; ++s) {
        const double t = (j + unit(*rng)) * horizon / strata;
        Eigen::Vector2d mu;
        Eigen::Matrix2d cov;
        d.Position(t, r, &mu, &cov);
        const Eigen::Matrix2d l = Eigen::LLT<Eigen::Matrix2d>(cov).matrixL();
        const Eigen::Vector2d x = mu + l * Eigen::Vector2d(normal(*rng), normal(*rng));
        const double p = map.Probability(x.x(), x.y(), &ws);
        sum += p;
        sum2 += p * p;
      }
      const double m = sum / per_stratum;
      mean_r += m / strata;
      var_r += std::max(0.0, sum2 / per_stratum - m * m) / (per_stratum - 1) / (strata * strata);
    }
    c += d.alpha(r) * mean_r;
    var += d.alpha(r) * d.alpha(r) * var_r;
  }
  return {c, std::sqrt(var)};
}

/// C of the ground truth itself: the time-averaged occupancy along the true future at the
/// predicted steps, 1/f sum_k p(m=1 | x_k) (the right-end rule's C of a distribution collapsing
/// onto the truth). Above epsilon, the map says the truth "collides": no compliant prediction can
/// then sit on it, whatever the solver does.
double TruthCost(const Eigen::MatrixX2d& truth, const occupancy::Map& map,
                 occupancy::MapWorkspace* ws) {
  double sum = 0;
  for (Eigen::Index k = 0; k < truth.rows(); ++k)
    sum += map.Probability(truth(k, 0), truth(k, 1), ws);
  return sum / static_cast<double>(truth.rows());
}

struct Accuracy {
  std::vector<double> err_mc, se_mc, err_order, err_time, err_converged, err_cmc, se_cmc;
  void Add(double cost, const std::pair<double, double>& mc, double reference, double fine) {
    err_mc.push_back(std::abs(cost - mc.first));
    se_mc.push_back(mc.second);
    err_order.push_back(std::abs(cost - reference));
    err_time.push_back(std::abs(cost - fine));
  }
  /// Against the converged quadrature and the continuous-time Monte Carlo estimate of C.
  void AddContinuous(double cost, double converged, const std::pair<double, double>& cmc) {
    err_converged.push_back(std::abs(cost - converged));
    err_cmc.push_back(std::abs(cost - cmc.first));
    se_cmc.push_back(cmc.second);
  }
  JsonObject Json(int order, int reference_order) const {
    // A non-finite entry (a cost that could not be computed) makes the maximum NaN (null).
    auto max_of = [](const std::vector<double>& v) {
      double m = v.empty() ? NAN : 0.0;
      for (double x : v) m = std::isfinite(x) && std::isfinite(m) ? std::max(m, x) : NAN;
      return m;
    };
    auto mean_of = [](const std::vector<double>& v) {
      double s = 0;
      for (double x : v) s += x;
      return v.empty() ? NAN : s / static_cast<double>(v.size());
    };
    JsonObject o;
    o.Set("windows", static_cast<int>(err_mc.size())).Set("order", order);
    o.Set("max_abs_error_vs_monte_carlo", max_of(err_mc));
    o.Set("mean_abs_error_vs_monte_carlo", mean_of(err_mc));
    o.Set("max_monte_carlo_standard_error", max_of(se_mc));
    o.Set("reference_order", reference_order);
    o.Set("max_abs_error_vs_reference_order", max_of(err_order));
    o.Set("max_abs_change_with_4x_time_points", max_of(err_time));
    // The error of C itself (quadrature in space and time): against the converged quadrature
    // (order kConvergedOrder, kConvergedPointsPerStep midpoints per step) and against Monte Carlo
    // in continuous time (no time grid at all).
    o.Set("max_abs_error_vs_converged", max_of(err_converged));
    o.Set("mean_abs_error_vs_converged", mean_of(err_converged));
    o.Set("max_abs_error_vs_continuous_monte_carlo", max_of(err_cmc));
    o.Set("max_continuous_monte_carlo_standard_error", max_of(se_cmc));
    return o;
  }
};

Eigen::MatrixX2d Rows(const Eigen::MatrixXd& rows, int k, int n) {
  Eigen::MatrixX2d out(n, 2);
  for (int i = 0; i < n; ++i) out.row(i) << rows(k, 2 * i), rows(k, 2 * i + 1);
  return out;
}

/// The converged quadrature every configured one is compared with: Gauss-Hermite order 32 and 16
/// midpoints per prediction step (the midpoint rule's error falls as 1/K^2; at 16 points per step
/// it is far below the 1e-3 asked of C). Above every candidate order, so that no candidate is
/// judged against itself; the continuous-time Monte Carlo check in eval.json is the independent
/// one.
constexpr int kConvergedOrder = 32;
constexpr int kConvergedPointsPerStep = 16;

/// Mixture C of d on `map` with the given order and time points (a throwaway operator).
double CostWith(const occupancy::Map* map, const TimeBasis& basis, const Eigen::VectorXd& times,
                int order, const TrajectoryDistribution& d) {
  ProjectorOptions po;
  po.order = order;
  DistributionProjector op(map, basis, times, po);
  DistributionProjector::Workspace ws = op.MakeWorkspace();
  return op.Cost(d, &ws);
}

/// The projector options of a run at Gauss-Hermite order `order`, without a check operator.
ProjectorOptions PlainProjectorOptions(const ExperimentConfig& c, int order) {
  ProjectorOptions po;
  po.epsilon = c.constraint.epsilon;
  po.margin = c.constraint.margin;
  po.order = order;
  po.solver.max_evaluations = c.constraint.max_evaluations;
  po.solver.max_seconds = c.constraint.max_seconds;
  po.solver.restarts = c.constraint.restarts;
  po.solver.feasibility_phase = c.constraint.feasibility_phase;
  // The solver accepts C within its tolerance of its target; the target sits `margin` below
  // epsilon, so a tolerance below the margin keeps accepted points compliant.
  po.solver.tolerance = std::min(po.solver.tolerance, 0.5 * c.constraint.margin);
  return po;
}

/// Quadrature candidates (Gauss-Hermite order x time points per step) scored by their largest
/// |C - converged C| over a set of distributions.
struct Candidates {
  std::vector<double> orders, substeps, max_errors;  ///< every candidate, in trial order
  int windows = 0;                                   ///< distributions scored
  int chosen = -1;
  bool met = false;

  Candidates(std::initializer_list<int> order_list, std::initializer_list<int> substep_list,
             int above = 0) {
    for (int o : order_list)
      for (int st : substep_list)
        if (o > above) {
          orders.push_back(o);
          substeps.push_back(st);
          max_errors.push_back(0.0);
        }
  }
  /// Scores every candidate on d (time points placed by `rule`; f prediction steps over horizon).
  void Score(const occupancy::Map* map, const TimeBasis& basis, TimeRule rule, double horizon,
             int f, const TrajectoryDistribution& d) {
    const double converged =
        CostWith(map, basis, RuleTimes(TimeRule::kMidpoint, horizon, f * kConvergedPointsPerStep),
                 kConvergedOrder, d);
    for (std::size_t k = 0; k < max_errors.size(); ++k) {
      const double e =
          std::abs(CostWith(map, basis, RuleTimes(rule, horizon, f * static_cast<int>(substeps[k])),
                            static_cast<int>(orders[k]), d) -
                   converged);
      // A non-finite cost or reference disqualifies the candidate.
      max_errors[k] = std::isfinite(e) ? std::max(max_errors[k], e) : INFINITY;
    }
    ++windows;
  }
  /// The cheapest candidate (order^2 x substeps map queries per step) within `accuracy`; if none
  /// is, the cheapest within 10 % of the most accurate one's error (met = false).
  void Choose(double accuracy) {
    if (max_errors.empty()) return;
    const double lowest = *std::min_element(max_errors.begin(), max_errors.end());
    met = lowest <= accuracy;
    const double allowed = met ? accuracy : 1.1 * lowest;
    double best_work = INFINITY;
    for (std::size_t k = 0; k < max_errors.size(); ++k) {
      const double work = orders[k] * orders[k] * substeps[k];
      if (max_errors[k] <= allowed && work < best_work) {
        chosen = static_cast<int>(k);
        best_work = work;
      }
    }
  }
  int order() const { return static_cast<int>(orders[static_cast<std::size_t>(chosen)]); }
  int substep() const { return static_cast<int>(substeps[static_cast<std::size_t>(chosen)]); }
  double error() const { return max_errors[static_cast<std::size_t>(chosen)]; }
  JsonObject Json() const {
    JsonObject o;
    o.Set("windows", windows).Set("met", met);
    if (chosen >= 0)
      o.Set("order", order()).Set("substeps", substep()).Set("max_abs_error", error());
    o.Set("candidate_orders", orders).Set("candidate_substeps", substeps);
    o.Set("candidate_max_abs_error", max_errors);
    return o;
  }
};

/// The quadratures chosen on validation windows (constraint.choose_quadrature, choose_check).
struct QuadratureChoice {
  Candidates rule{{2, 3, 4, 5, 6, 8, 10, 12, 16, 20}, {1, 2, 3, 4}};
  std::optional<Candidates> check;
  double check_accuracy = 0;
  JsonObject Json(double accuracy) const {
    JsonObject o = rule.Json();
    o.Set("accuracy", accuracy);
    if (check) o.Set("check_accuracy", check_accuracy);
    o.Set("converged_order", kConvergedOrder);
    o.Set("converged_points_per_step", kConvergedPointsPerStep);
    if (check) o.Set("check", check->Json());
    return o;
  }
};

/// Chooses the Gauss-Hermite order and time points per step on the priors of `choice_windows`
/// validation windows (evenly spread over the split): the cheapest candidate whose C is within
/// `accuracy` of the converged C on every window (Candidates::Choose). The test split is never
/// read. `met` speaks of priors only: a projected result sits where the solver pushed it, often on
/// a wall, where the chosen rule may be far less accurate. So with `choose_check`, validation
/// windows (all of them, in a spread-out order) whose prior violates under the chosen rule are
/// projected with it, up to `choice_windows` of them, and the check operator (midpoints; orders
/// above the rule's) is chosen the same way on the projected results.
QuadratureChoice ChooseQuadrature(const ExperimentConfig& c, const ConstrainedData& d,
                                  const span::Predictor& prior, const std::string& run_dir) {
  const std::vector<MapScene>& scenes = d.split.val;
  FitSceneMaps(c, scenes, run_dir);
  const int p = c.windows.observed, f = c.windows.predicted;
  const double horizon = f * d.val.windows.seconds_per_step;
  QuadratureChoice q;
  const int n_val = d.val.windows.size();
  const int n = std::min(n_val, c.constraint.choice_windows);
  std::vector<std::unique_ptr<occupancy::Map>> maps(scenes.size());
  const auto map_of_window = [&](int w) {  // loaded on first use
    const auto s = static_cast<std::size_t>(d.val.scene[static_cast<std::size_t>(w)]);
    if (!maps[s]) maps[s] = occupancy::LoadMap(run_dir + "/" + SceneMapFile(scenes[s]));
    return maps[s].get();
  };
  span::Predictor::Workspace pws = prior.MakeWorkspace();
  TrajectoryDistribution dist = prior.MakeDistribution(), opt = prior.MakeDistribution();
  for (int i = 0; i < n; ++i) {
    const int w = static_cast<int>(static_cast<std::int64_t>(i) * n_val / n);
    prior.Predict(Rows(d.val.windows.past, w, p), &pws, &dist);
    q.rule.Score(map_of_window(w), prior.basis(), c.constraint.time_rule, horizon, f, dist);
  }
  q.rule.Choose(c.constraint.accuracy);
  log::Info("constrained: quadrature chosen on ", q.rule.windows, " validation priors: order ",
            q.rule.order(), ", ", q.rule.substep(), " time points per step (max |C - converged| ",
            q.rule.error(), q.rule.met ? ", meets " : ", misses ", c.constraint.accuracy, ")");
  if (!c.constraint.choose_check) return q;

  q.check.emplace(std::initializer_list<int>{8, 10, 12, 16, 20, 24},
                  std::initializer_list<int>{1, 2, 4}, q.rule.order());
  const Eigen::VectorXd times = RuleTimes(c.constraint.time_rule, horizon, f * q.rule.substep());
  const ProjectorOptions po = PlainProjectorOptions(c, q.rule.order());
  // Every validation window in a spread-out order (a stride coprime to their number), until
  // `choice_windows` of them needed projecting.
  std::int64_t stride = 7919;
  while (std::gcd(stride, static_cast<std::int64_t>(n_val)) != 1) stride += 2;
  for (std::int64_t i = 0; i < n_val && q.check->windows < c.constraint.choice_windows; ++i) {
    const int w = static_cast<int>(i * stride % n_val);
    const occupancy::Map* map = map_of_window(w);
    prior.Predict(Rows(d.val.windows.past, w, p), &pws, &dist);
    const DistributionProjector projector(map, prior.basis(), times, po);
    DistributionProjector::Workspace ws = projector.MakeWorkspace();
    if (projector.Project(dist, &opt, &ws).changed)
      q.check->Score(map, prior.basis(), TimeRule::kMidpoint, horizon, f, opt);
  }
  if (q.check->windows == 0 || q.check->orders.empty()) {
    log::Info("constrained: no validation prior needed projecting; the check stays at order ",
              c.constraint.check_order);
    q.check.reset();
    return q;
  }
  q.check->Choose(c.constraint.check_accuracy);
  q.check_accuracy = c.constraint.check_accuracy;
  log::Info("constrained: check chosen on ", q.check->windows,
            " projected validation windows: ", "order ", q.check->order(), ", ", q.check->substep(),
            " midpoints per step ", "(max |C - converged| ", q.check->error(),
            q.check->met ? ", meets " : ", misses ", c.constraint.check_accuracy, ")");
  return q;
}

}  // namespace

std::string EvaluateConstrained(const ExperimentConfig& c, const ConstrainedData& d,
                                const std::string& run_dir) {
  const RunArtifacts art = ArtifactsOf(c, run_dir);
  for (const std::string& a : {art.prior, art.ktm, art.naive})
    FS_THROW_UNLESS(a.empty() || fs::exists(a), a, " is missing; train (or export) the run first");
  const span::Predictor prior = span::Predictor::Load(art.prior);
  FS_THROW_UNLESS(prior.layout().u_param == UParam::kDiagonal, art.prior,
                  ": the prior's U is not diagonal (network.u_param must be diagonal)");
  std::optional<span::Predictor> ktm;
  if (!art.ktm.empty()) ktm = span::Predictor::Load(art.ktm);
  std::optional<NaivePredictor> naive;
  if (!art.naive.empty()) naive = NaivePredictor::Load(art.naive);

  const std::vector<MapScene>& scenes = d.split.test;
  FitSceneMaps(c, scenes, run_dir);
  const int p = c.windows.observed, f = c.windows.predicted;
  const double dt = d.test.windows.seconds_per_step;
  FS_THROW_UNLESS(prior.observed() == p && std::abs(prior.seconds_per_step() - dt) < 1e-9,
                  art.prior, ": trained on ", prior.observed(), " observed points every ",
                  prior.seconds_per_step(), " s; the config's windows have ", p, " every ", dt,
                  " s");
  // Gauss-Hermite order and time points: configured, or chosen on validation windows.
  std::optional<QuadratureChoice> choice;
  if (c.constraint.choose_quadrature) choice = ChooseQuadrature(c, d, prior, run_dir);
  const int order = choice ? choice->rule.order() : c.constraint.order;
  const int substeps = choice ? choice->rule.substep() : c.constraint.substeps;
  const bool check_chosen = choice && choice->check;
  int check_order = check_chosen ? choice->check->order() : c.constraint.check_order;
  if (choice && !check_chosen && check_order > 0 && check_order <= order) {
    // No validation window needed projecting, and the configured check is no finer than the rule
    // chosen: a check a few orders above it instead.
    check_order = std::min(64, order + 4);
    log::Info("constrained: constraint.check_order ", c.constraint.check_order,
              " does not exceed the chosen order ", order, "; checking at order ", check_order);
  }
  const int check_substeps = check_chosen ? choice->check->substep() : c.constraint.check_substeps;
  FS_THROW_UNLESS(check_order == 0 || check_order > order, "constraint.check_order (", check_order,
                  ") must exceed the Gauss-Hermite order it checks (", order,
                  choice ? ", chosen on validation)" : ", constraint.order)");
  // The rectangle rule of C over (0, f dt]: `substeps` points per prediction step where the time
  // rule puts them; the check of its accuracy uses 4 times as many, and the converged reference.
  const double horizon = f * dt;
  const int k = f * substeps;
  const Eigen::VectorXd times = RuleTimes(c.constraint.time_rule, horizon, k);
  const Eigen::VectorXd fine_times = RuleTimes(c.constraint.time_rule, horizon, 4 * k);
  const Eigen::VectorXd converged_times =
      RuleTimes(TimeRule::kMidpoint, horizon, f * kConvergedPointsPerStep);
  const Eigen::VectorXd steps = RuleTimes(TimeRule::kRight, horizon, f);  // for pictures
  ProjectorOptions po = PlainProjectorOptions(c, order);
  po.check_order = check_order;
  po.check_rounds = c.constraint.check_rounds;
  // A chosen check accepts C <= epsilon - its validated error (capped below the margin).
  if (check_chosen) po.check_slack = std::min(choice->check->error(), 0.5 * c.constraint.margin);
  const Eigen::VectorXd check_times = RuleTimes(TimeRule::kMidpoint, horizon, f * check_substeps);
  constexpr int kReferenceOrder = 20;
  ProjectorOptions po_plain = po;  // the configured operator alone (no check)
  po_plain.check_order = 0;
  ProjectorOptions po_ref = po_plain;
  po_ref.order = kReferenceOrder;
  ProjectorOptions po_converged = po_ref;
  po_converged.order = kConvergedOrder;

  struct SceneRuntime {
    std::unique_ptr<occupancy::Map> map;
    std::unique_ptr<DistributionProjector> projector, reference, fine, converged;
    // One workspace per operator: each is sized for its map, order and time points.
    std::optional<DistributionProjector::Workspace> ws, ws_reference, ws_fine, ws_converged;
    occupancy::MapWorkspace map_ws;
  };
  std::vector<SceneRuntime> rt(scenes.size());
  auto runtime = [&](int s) -> SceneRuntime& {
    SceneRuntime& r = rt[static_cast<std::size_t>(s)];
    if (!r.map) {
      r.map = occupancy::LoadMap(run_dir + "/" + SceneMapFile(scenes[static_cast<std::size_t>(s)]));
      r.projector = po.check_order > 0 ? std::make_unique<DistributionProjector>(
                                             r.map.get(), prior.basis(), times, po, check_times)
                                       : std::make_unique<DistributionProjector>(
                                             r.map.get(), prior.basis(), times, po);
      r.reference =
          std::make_unique<DistributionProjector>(r.map.get(), prior.basis(), times, po_ref);
      r.fine =
          std::make_unique<DistributionProjector>(r.map.get(), prior.basis(), fine_times, po_plain);
      r.converged = std::make_unique<DistributionProjector>(r.map.get(), prior.basis(),
                                                            converged_times, po_converged);
      r.ws = r.projector->MakeWorkspace();
      r.ws_reference = r.reference->MakeWorkspace();
      r.ws_fine = r.fine->MakeWorkspace();
      r.ws_converged = r.converged->MakeWorkspace();
      r.map_ws = r.map->MakeWorkspace();
    }
    return r;
  };

  const int n_all = d.test.windows.size();
  const int n = c.eval.max_windows > 0 ? std::min(n_all, c.eval.max_windows) : n_all;
  span::Predictor::Workspace pws = prior.MakeWorkspace();
  TrajectoryDistribution dist = prior.MakeDistribution(), opt = prior.MakeDistribution();
  std::optional<span::Predictor::Workspace> kws;
  std::optional<TrajectoryDistribution> kdist;
  if (ktm) {
    kws = ktm->MakeWorkspace();
    kdist = ktm->MakeDistribution();
  }
  std::optional<NaivePredictor::Workspace> nws;
  if (naive) nws = naive->MakeWorkspace();
  Eigen::Matrix<double, Eigen::Dynamic, 2> naive_out(f, 2);

  Block b_prior, b_opt, b_prior_v, b_opt_v, b_ktm, b_cv, b_naive;
  std::vector<double> truth_costs;  // C of each window's ground truth (TruthCost)
  std::map<std::string, int> statuses;
  std::vector<double> solve_s, check_s;
  int failures = 0, kl_windows = 0;
  double kl_sum = 0;
  Accuracy acc, acc_opt;
  // The optimised C of projected windows under a finer quadrature and a finer time grid: the
  // solver drove the configured operator down, so compliance is also checked by the others.
  int opt_violating_reference = 0, opt_violating_fine = 0, opt_violating_converged = 0;
  int check_resolved = 0;  // windows solved again because the check operator found them above
  std::mt19937_64 rng(static_cast<std::uint64_t>(c.eval.sample_seed));
  std::vector<std::pair<int, WindowPicture>> pictures;
  std::ostringstream csv;
  csv << "window,scene,prior_cost,cost,status,seconds,evaluations,kl,prior_ade,optimised_ade,"
         "prior_fde,optimised_fde\n";
  for (int w = 0; w < n; ++w) {
    const int s = d.test.scene[static_cast<std::size_t>(w)];
    SceneRuntime& r = runtime(s);
    DistributionProjector::Workspace* pw = &*r.ws;
    const Eigen::MatrixX2d past = Rows(d.test.windows.past, w, p);
    const Eigen::MatrixX2d truth = Rows(d.test.windows.future, w, f);
    prior.Predict(past, &pws, &dist);
    const TrackProjection tp = r.projector->Project(dist, &opt, pw);
    const PredictionScores sp = ScorePrediction(dist, truth, dt);
    const PredictionScores so = ScorePrediction(opt, truth, dt);
    // The run's verdict on the result: the check operator's C when there is one.
    const double opt_cost = std::isfinite(tp.checked_cost) ? tp.checked_cost : tp.cost;
    const double prior_converged = r.converged->Cost(dist, &*r.ws_converged);
    // An unchanged window's result is its prior: its converged C is already known.
    const double opt_converged =
        tp.changed ? r.converged->Cost(opt, &*r.ws_converged) : prior_converged;
    b_prior.Add(sp);
    b_prior.AddCost(tp.prior_cost, c.constraint.epsilon);
    b_prior.AddConvergedCost(prior_converged, c.constraint.epsilon);
    b_opt.Add(so);
    b_opt.AddCost(opt_cost, c.constraint.epsilon);
    b_opt.AddConvergedCost(opt_converged, c.constraint.epsilon);
    check_resolved += tp.check_rounds > 0;
    if (tp.prior_cost - c.constraint.epsilon > 0) {
      b_prior_v.Add(sp);
      b_prior_v.AddCost(tp.prior_cost, c.constraint.epsilon);
      b_prior_v.AddConvergedCost(prior_converged, c.constraint.epsilon);
      b_opt_v.Add(so);
      b_opt_v.AddCost(opt_cost, c.constraint.epsilon);
      b_opt_v.AddConvergedCost(opt_converged, c.constraint.epsilon);
    }
    ++statuses[tp.status];
    if (!tp.feasible) ++failures;
    (tp.changed ? solve_s : check_s).push_back(tp.seconds);
    if (tp.changed) {
      kl_sum += tp.kl;
      ++kl_windows;
    }
    truth_costs.push_back(TruthCost(truth, *r.map, &r.map_ws));
    // Monte Carlo in continuous time: strata of a quarter step.
    const int strata = 4 * f;
    if (w < c.eval.accuracy_windows) {
      acc.Add(tp.prior_cost, MonteCarloCost(dist, times, *r.map, c.eval.accuracy_samples, &rng),
              r.reference->Cost(dist, &*r.ws_reference), r.fine->Cost(dist, &*r.ws_fine));
      acc.AddContinuous(
          tp.prior_cost, prior_converged,
          ContinuousMonteCarloCost(dist, horizon, *r.map, c.eval.accuracy_samples, strata, &rng));
    }
    if (tp.changed) {
      const double reference = r.reference->Cost(opt, &*r.ws_reference);
      const double fine = r.fine->Cost(opt, &*r.ws_fine);
      opt_violating_reference += !(reference <= c.constraint.epsilon);
      opt_violating_fine += !(fine <= c.constraint.epsilon);
      opt_violating_converged += !(opt_converged <= c.constraint.epsilon);
      if (static_cast<int>(acc_opt.err_mc.size()) < c.eval.accuracy_windows) {
        acc_opt.Add(tp.cost, MonteCarloCost(opt, times, *r.map, c.eval.accuracy_samples, &rng),
                    reference, fine);
        acc_opt.AddContinuous(
            tp.cost, opt_converged,
            ContinuousMonteCarloCost(opt, horizon, *r.map, c.eval.accuracy_samples, strata, &rng));
      }
    }
    if (ktm) {
      ktm->Predict(past, &*kws, &*kdist);
      b_ktm.Add(ScorePrediction(*kdist, truth, dt));
      b_ktm.AddCost(r.projector->Cost(*kdist, pw), c.constraint.epsilon);
      b_ktm.AddConvergedCost(r.converged->Cost(*kdist, &*r.ws_converged), c.constraint.epsilon);
    }
    b_cv.Add(ScorePoints(ConstantVelocity(past, f), truth));
    if (naive) {
      naive->Predict(past, &*nws, naive_out);
      b_naive.Add(ScorePoints(naive_out, truth));
    }
    csv << w << ',' << scenes[static_cast<std::size_t>(s)].name << ',' << tp.prior_cost << ','
        << tp.cost << ',' << tp.status << ',' << tp.seconds << ',' << tp.evaluations << ',' << tp.kl
        << ',' << sp.ade_nearest << ',' << so.ade_nearest << ',' << sp.fde_nearest << ','
        << so.fde_nearest << '\n';
    if (tp.changed && static_cast<int>(pictures.size()) < c.eval.plot_windows)
      pictures.push_back({s, WindowPicture{past, truth, dist, opt, tp.prior_cost, tp.cost}});
  }
  WriteFileAtomically(run_dir + "/tracks.csv", csv.str());

  if (!pictures.empty()) {
    fs::create_directories(run_dir + "/plots");
    for (std::size_t i = 0; i < pictures.size(); ++i)
      DrawWindowPicture(run_dir + "/plots/window_" + std::to_string(i) + ".png",
                        scenes[static_cast<std::size_t>(pictures[i].first)].raster,
                        pictures[i].second, steps, order, c.eval.plot_samples,
                        static_cast<std::uint64_t>(c.eval.sample_seed) + i);
  }

  // Validation windows (prior and KTM only, no projection): what hyper-parameters are chosen by.
  Block v_prior, v_ktm;
  const int n_val = c.eval.max_windows > 0 ? std::min(d.val.windows.size(), c.eval.max_windows)
                                           : d.val.windows.size();
  for (int w = 0; w < n_val; ++w) {
    const Eigen::MatrixX2d past = Rows(d.val.windows.past, w, p);
    const Eigen::MatrixX2d truth = Rows(d.val.windows.future, w, f);
    prior.Predict(past, &pws, &dist);
    v_prior.Add(ScorePrediction(dist, truth, dt));
    if (ktm) {
      ktm->Predict(past, &*kws, &*kdist);
      v_ktm.Add(ScorePrediction(*kdist, truth, dt));
    }
  }

  JsonObject data;
  data.Set("source", c.data.source).Set("scenes", d.report.scenes);
  data.Set("map_kind", c.map.kind == occupancy::RasterMapKind::kGrid ? "grid" : "fast_bhm");
  data.Set("tracks_read", d.report.tracks_read).Set("tracks_kept", d.report.tracks_kept);
  data.Set("tracks_too_short", d.report.too_short);
  data.Set("tracks_outside_map_frame", d.report.outside_frame);
  data.Set("samples_in_obstacles", d.report.points_in_obstacles);
  data.Set("tracks_in_obstacles", d.report.tracks_in_obstacles);
  data.Set("train_windows", d.train.windows.size()).Set("val_windows", d.val.windows.size());
  data.Set("test_windows", n_all).Set("evaluated_windows", n);
  data.Set("seconds_per_step", dt).Set("observed", p).Set("predicted", f);
  JsonObject status;
  for (const auto& [name, count] : statuses) status.Set(name, count);
  JsonObject solve;
  solve.Set("epsilon", c.constraint.epsilon).Set("order", order);
  solve.Set("time_points", k).Set("substeps", substeps);
  solve.Set("time_rule", c.constraint.time_rule == TimeRule::kMidpoint ? "midpoint" : "right");
  solve.Set("statuses", status).Set("failures", failures);
  solve.Set("check_order", check_order);
  if (check_order > 0) {
    solve.Set("check_substeps", check_substeps);
    solve.Set("check_time_points", static_cast<int>(check_times.size()));
    solve.Set("check_rounds", c.constraint.check_rounds).Set("check_slack", po.check_slack);
    solve.Set("windows_solved_again_after_check", check_resolved);
  }
  solve.Set("projected", static_cast<int>(solve_s.size()));
  solve.Set("optimised_violating_at_reference_order", opt_violating_reference);
  solve.Set("optimised_violating_with_4x_time_points", opt_violating_fine);
  solve.Set("optimised_violating_at_converged", opt_violating_converged);
  solve.Set("mean_kl_of_projected", kl_windows > 0 ? kl_sum / kl_windows : NAN);
  solve.Set("solve_time_ms", Percentiles(solve_s, 1e3));
  solve.Set("unprojected_time_ms", Percentiles(check_s, 1e3));
  JsonObject o;
  o.Set("kind", "constrained").Set("data", data);
  o.Set("prior", b_prior.Json()).Set("optimised", b_opt.Json());
  o.Set("prior_on_violating", b_prior_v.Json()).Set("optimised_on_violating", b_opt_v.Json());
  if (ktm) o.Set("ktm", b_ktm.Json());
  o.Set("cv", b_cv.Json());
  if (naive) o.Set("naive", b_naive.Json());
  JsonObject val;
  val.Set("prior", v_prior.Json());
  if (ktm) val.Set("ktm", v_ktm.Json());
  o.Set("val", val);
  o.Set("solve", solve);
  // The ground truth's own C: how often the map says the true future collides.
  JsonObject truth;
  {
    int violating = 0;
    double sum = 0;
    for (double tc : truth_costs) {
      violating += !(tc <= c.constraint.epsilon);
      sum += tc;
    }
    const double kn = truth_costs.empty() ? NAN : 1.0 / static_cast<double>(truth_costs.size());
    truth.Set("windows", static_cast<int>(truth_costs.size()));
    truth.Set("mean_cost", sum * kn).Set("median_cost", Percentile(truth_costs, 50));
    truth.Set("p90_cost", Percentile(truth_costs, 90));
    truth.Set("violating", violating).Set("cvp", violating * kn);
  }
  o.Set("truth", truth);
  if (choice) o.Set("quadrature_choice", choice->Json(c.constraint.accuracy));
  o.Set("quadrature_accuracy", acc.Json(order, kReferenceOrder));
  o.Set("quadrature_accuracy_optimised", acc_opt.Json(order, kReferenceOrder));
  o.Set(
      "notes",
      "ade/fde: the mean of the component nearest to the truth (thesis); *_mixture_mean: of the "
      "mixture mean; al: mean over steps of the mixture density of the truth (1/m^2); cvp: share "
      "of windows with C - epsilon > 0; cv and naive are point predictions (no al); solve_time_ms: "
      "windows whose prior violated the constraint (one core), unprojected_time_ms: the others "
      "(with a check operator, its verification included); cvp: C under the run's operators (the "
      "check operator's verdict on optimised results), cvp_converged: under the converged "
      "quadrature; truth: "
      "the time-averaged p(m=1|x) along each window's true future at the predicted steps");
  const std::string json = o.Dump() + "\n";
  WriteFileAtomically(run_dir + "/eval.json", json);
  log::Info("constrained eval: prior ADE ", b_prior.ade_n / std::max(1, b_prior.n), " CVP ",
            b_prior.violating, "/", b_prior.n, " -> optimised ADE ",
            b_opt.ade_n / std::max(1, b_opt.n), " CVP ", b_opt.violating, "/", b_opt.n,
            ", failures ", failures);
  return json;
}

}  // namespace foresight::constrained
