// Evaluation of task-space sets on the JACO arm (thesis ch 8, "Generalised Collision-Avoiding
// Motion Reproduction"): see eval.h. Everything is measured in metres: the end-effector path
// against the demonstrations (Frechet), the arm's body balls against the cylinder (MCD).

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "core/bench.h"
#include "core/error.h"
#include "core/log.h"
#include "datasets/data_root.h"
#include "inference/imitation/cspace.h"
#include "inference/imitation/eflow.h"
#include "inference/imitation/metrics.h"
#include "inference/imitation/template_artifact.h"
#include "models/imitation/occupancy_fit.h"
#include "training/diffeo/eval.h"
#include "training/diffeo/eval_common.h"

namespace foresight::imitation {
namespace {

/// A C-space path: joint configurations and the end-effector path, and whether it reached.
struct ArmPath {
  Eigen::Matrix<double, kArmDof, Eigen::Dynamic> joints;
  Eigen::Matrix3Xd end_effector;
  bool reached = false;
};

ArmPath FromRollout(const CSpaceRollout& r) { return {r.joints, r.end_effector, r.reached()}; }

/// Rolls out q_dot = velocity(q) (Euler) until the end effector is within tolerance of the goal.
ArmPath RollOutArm(const SerialChain& chain, const std::function<ArmVector(const ArmVector&)>& f,
                   const ArmVector& start, const Eigen::Vector3d& goal, const RolloutSettings& r) {
  ChainData data = chain.MakeData();
  std::vector<ArmVector> qs{start};
  std::vector<Eigen::Vector3d> xs;
  ArmPath out;
  ArmVector q = start;
  for (int k = 0;; ++k) {
    Kinematics(chain, q, &data);
    xs.push_back(data.p_ee);
    if ((data.p_ee - goal).norm() <= r.goal_tolerance) {
      out.reached = true;
      break;
    }
    if (k >= r.max_steps) break;
    const ArmVector v = f(q);
    if (!v.allFinite()) break;
    ArmVector step = r.dt * v;
    const double length = step.cwiseAbs().maxCoeff();
    if (r.max_step_length > 0 && length > r.max_step_length) step *= r.max_step_length / length;
    q += step;
    qs.push_back(q);
  }
  qs.resize(xs.size());
  out.joints.resize(kArmDof, static_cast<Eigen::Index>(qs.size()));
  out.end_effector.resize(3, static_cast<Eigen::Index>(xs.size()));
  for (std::size_t i = 0; i < qs.size(); ++i) {
    out.joints.col(static_cast<Eigen::Index>(i)) = qs[i];
    out.end_effector.col(static_cast<Eigen::Index>(i)) = xs[i];
  }
  return out;
}

/// Damped pseudo-inverse velocity J' (J J' + lambda^2 I)^-1 v of the end effector.
ArmVector PullBack(const ChainData& data, const Eigen::Vector3d& v) {
  constexpr double kLambda = CSpaceSystem::kDefaultDamping;
  const Eigen::Matrix3d JJt =
      data.J_ee * data.J_ee.transpose() + kLambda * kLambda * Eigen::Matrix3d::Identity();
  return data.J_ee.transpose() * JJt.ldlt().solve(v);
}

/// The largest depth of any body ball inside the obstacle along the paths (m).
double BodyDepth(const SerialChain& chain, const std::vector<ArmPath>& paths,
                 const CylinderObstacle& cyl) {
  ChainData data = chain.MakeData();
  double worst = 0;
  for (const ArmPath& p : paths)
    for (Eigen::Index k = 0; k < p.joints.cols(); ++k) {
      Kinematics(chain, p.joints.col(k), &data);
      for (int j = 0; j < chain.num_points(); ++j)
        worst = std::max(worst, chain.points()[static_cast<std::size_t>(j)].radius -
                                    cyl.SignedDistance(data.p.col(j)));
    }
  return std::max(0.0, worst);
}

/// The largest map probability at any body point along the paths.
double BodyMapProbability(const SerialChain& chain, const OccupancyField<3>& field,
                          const std::vector<ArmPath>& paths) {
  ChainData data = chain.MakeData();
  auto ws = field.MakeWorkspace();
  double worst = 0;
  for (const ArmPath& p : paths)
    for (Eigen::Index k = 0; k < p.joints.cols(); ++k) {
      Kinematics(chain, p.joints.col(k), &data);
      for (int j = 0; j < chain.num_points(); ++j)
        worst = std::max(worst, field.Probability(data.p.col(j), ws.get()));
    }
  return worst;
}

bool AllReached(const std::vector<ArmPath>& paths) {
  return std::all_of(paths.begin(), paths.end(), [](const ArmPath& p) { return p.reached; });
}

/// End-effector paths in the model's normalised coordinates (for AddPathScores).
PathSet Normalised(const std::vector<ArmPath>& paths, const TaskNormalisation& tn) {
  PathSet s;
  for (const ArmPath& p : paths) {
    s.paths.push_back(((p.end_effector.colwise() - tn.offset) * tn.scale).eval());
    s.reached.push_back(p.reached ? 1 : 0);
  }
  return s;
}

}  // namespace

Scores EvaluateTaskSpaceShape(const ExperimentConfig& c, const PreparedDemos& demos,
                              const std::string& template_path, const std::string& eflow_path,
                              const std::string& plot_dir) {
  (void)plot_dir;  // no picture of the arm yet
  const TemplateArtifact<3> art = LoadTemplate<3>(template_path);
  const SerialChain chain =
      SerialChain::LoadJaco(ResolveDataFile(c.data.root, "kinova_jaco_j2n6s300"));
  TaskNormalisation tn;
  tn.offset = art.normalisation.offset;
  tn.scale = art.normalisation.scale;
  const double metres = 1.0 / tn.scale;  // normalised unit -> m
  const CSpaceSystem plain(chain, art.system, tn);
  const Eigen::Vector3d goal = plain.goal();
  RolloutSettings roll;
  roll.dt = c.eval.dt;
  roll.max_steps = c.eval.max_steps;
  roll.goal_tolerance = c.eval.goal_tolerance * metres;
  roll.max_step_length = c.eval.max_joint_step;

  // Start configurations: inverse kinematics of every demo start from the same initial guess.
  const int n = static_cast<int>(demos.demos.demos.size());
  std::vector<ArmVector> starts;
  ArmVector seed_q;
  seed_q << 0, 3.6, 1.4, 0, 1.0, 0;  // elbow up, hand down in front of the base
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x0 =
        tn.ToWorld(demos.demos.demos[static_cast<std::size_t>(i)].position.col(0));
    ArmVector q;
    FS_THROW_UNLESS(InverseKinematics(chain, x0, seed_q, &q, 1e-6, 500), demos.name, ": demo ",
                    demos.original[static_cast<std::size_t>(i)], " starts at ", x0.transpose(),
                    " m, which the arm does not reach");
    starts.push_back(q);
  }
  Scores s;
  // ---- imitation pulled back to C-space ------------------------------------------------------
  std::vector<ArmPath> imit;
  for (const ArmVector& q : starts) imit.push_back(FromRollout(RollOutCSpace(plain, q, roll)));
  AddPathScores("", Normalised(imit, tn), demos, c.eval.resample, &s, {}, metres);
  {  // stability of the world-space system from a grid of starts (normalised units)
    FlowWorkspace<3> ws = art.system.flow().MakeWorkspace();
    RolloutSettings r = roll;
    r.goal_tolerance = c.eval.goal_tolerance;
    r.max_step_length = c.eval.max_step_length;
    int reached = 0;
    const auto grid = GridStarts<3>(demos.demos, c.eval.grid, 0.1);
    for (const Vec<3>& g : grid)
      reached += RollOut<3>([&](const Vec<3>& x) { return art.system.Velocity(x, &ws); }, g,
                            art.system.goal(), r)
                     .reached;
    s.push_back({"grid_reach_rate", reached / static_cast<double>(grid.size())});
  }
  // ---- EFlow pulled back the same way --------------------------------------------------------
  std::optional<EFlowModel> eflow;
  ChainData edata = chain.MakeData();
  const auto eflow_world = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return eflow->Velocity(tn.ToModel(x)) / tn.scale;
  };
  std::vector<ArmPath> er;
  if (!eflow_path.empty()) {
    eflow = EFlowModel::Load(eflow_path);
    const auto f = [&](const ArmVector& q) -> ArmVector {
      Kinematics(chain, q, &edata);
      return PullBack(edata, eflow_world(edata.p_ee));
    };
    for (const ArmVector& q : starts) er.push_back(RollOutArm(chain, f, q, goal, roll));
    AddPathScores("eflow_", Normalised(er, tn), demos, c.eval.resample, &s, {}, metres);
  }

  // ---- the cylinder on the demonstrations
  // --------------------------------------------------------
  if (c.obstacle.enabled) {
    const Eigen::Vector3d mid = tn.ToWorld(ObstacleCentre(demos, c.obstacle.fraction));
    CylinderObstacle cyl;
    cyl.axis_xy = mid.head<2>();
    cyl.z_min = 0;
    cyl.z_max = c.obstacle.height;
    cyl.radius = c.obstacle.radius;
    double ball = 0;
    for (const BodyPoint& b : chain.points()) ball = std::max(ball, b.radius);
    FS_THROW_UNLESS(cyl.SignedDistance(goal) > ball, demos.name, ": the obstacle (axis ",
                    cyl.axis_xy.transpose(), ", radius ", cyl.radius,
                    " m) covers the goal; move it (obstacle.fraction) or shrink it");
    // The map of the cylinder inflated by the largest body ball (body points enter by centres).
    const Vec<3> lo(cyl.axis_xy.x() - cyl.radius - ball, cyl.axis_xy.y() - cyl.radius - ball,
                    cyl.z_min - ball);
    const Vec<3> hi(cyl.axis_xy.x() + cyl.radius + ball, cyl.axis_xy.y() + cyl.radius + ball,
                    cyl.z_max + ball);
    const OccupancyField<3> field = FitObstacleMap<3>(
        c.obstacle, [&](const Vec<3>& p) { return cyl.SignedDistance(p) - ball; }, lo, hi,
        demos.name);
    s.push_back({"mcd", BodyDepth(chain, imit, cyl)});
    if (eflow) s.push_back({"eflow_mcd", BodyDepth(chain, er, cyl)});
    std::vector<ArmVector> train_starts;
    for (int i : demos.train) train_starts.push_back(starts[static_cast<std::size_t>(i)]);

    // The Euler step: obstacle.step, or less where the C-space field is steeper along the plain
    // rollouts (which cross the obstacle), so that h ||dV_q|| <= step_lipschitz there; halved below
    // when a flow time's map does not invert (obstacle.step_halvings).
    double max_dv = 0;
    {
      FlowSettings<kArmDof> unit;
      const CSpaceObstacleTransform probe(chain, field, unit);
      auto ws = probe.MakeWorkspace();
      ArmMatrix dv;
      for (const ArmPath& p : imit)
        for (Eigen::Index k = 0; k < p.joints.cols(); k += 2) {
          probe.Field(p.joints.col(k), &ws, &dv);
          max_dv = std::max(max_dv, dv.norm());  // Frobenius >= spectral
        }
    }
    const double h = std::min(c.obstacle.step, c.obstacle.step_lipschitz / std::max(max_dv, 1e-12));
    log::Info(demos.name, ": C-space obstacle field max |dV_q| ", max_dv, ", flow step ", h);
    const auto system_with = [&](double t, double step) {
      FlowSettings<kArmDof> fs;
      fs.time = t;
      fs.steps = ObstacleSteps(t, step);
      GoalGate gate;
      gate.goal = goal;
      gate.length = c.obstacle.goal_gate;
      return CSpaceSystem(chain, art.system, tn, CSpaceObstacleTransform(chain, field, fs, gate));
    };
    // Invertibility is checked along the rollouts (every configuration the arm passes).
    // Logs the worst round trip and the failures, so a refusal says why.
    const auto invertible = [&](const CSpaceSystem& sys, const std::vector<ArmPath>& rs) {
      auto ws = sys.obstacle()->MakeWorkspace();
      double worst = 0;
      int failed = 0, checked = 0;
      for (const ArmPath& p : rs)
        for (Eigen::Index k = 0; k < p.joints.cols(); k += 5) {
          ArmVector back;
          const ArmVector q = sys.obstacle()->Forward(p.joints.col(k), &ws);
          ++checked;
          if (!sys.obstacle()->Inverse(q, &ws, &back)) {
            ++failed;
            continue;
          }
          worst = std::max(worst, (back - p.joints.col(k)).norm());
        }
      log::Info(demos.name, ": C-space obstacle flow time ", sys.obstacle()->settings().time, " (",
                sys.obstacle()->settings().steps, " steps): ", failed, " of ", checked,
                " inverses did not converge, worst round trip ", worst, " rad");
      return failed == 0 && worst <= c.obstacle.inverse_tolerance;
    };
    // Each time with the coarsest step (h, h / 2, ... obstacle.step_halvings times) whose Euler
    // map inverts along its rollouts from the training starts.
    const FlowTimeChoice pick =
        ChooseFlowTime(c.obstacle.times, h, c.obstacle.step_halvings, [&](double t, double step) {
          const CSpaceSystem sys = system_with(t, step);
          std::vector<ArmPath> rs;
          for (const ArmVector& q : train_starts)
            rs.push_back(FromRollout(RollOutCSpace(sys, q, roll)));
          FlowTrial trial;
          trial.inverts = invertible(sys, rs);
          trial.clear = trial.inverts && AllReached(rs) &&
                        BodyMapProbability(chain, field, rs) < c.obstacle.clear_probability;
          return trial;
        });
    FS_THROW_UNLESS(pick.index >= 0, demos.name, ": obstacle.times[0] = ", c.obstacle.times[0],
                    " with obstacle.step ", c.obstacle.step, " and ", c.obstacle.step_halvings,
                    " halvings already makes the C-space obstacle flow non-invertible; lower both");
    const double chosen = c.obstacle.times[static_cast<std::size_t>(pick.index)];
    const bool cleared = pick.cleared;
    const CSpaceSystem avoid = system_with(chosen, pick.step);
    std::vector<ArmPath> ar;
    for (const ArmVector& q : starts) ar.push_back(FromRollout(RollOutCSpace(avoid, q, roll)));
    s.push_back({"obstacle_flow_time", chosen});
    s.push_back({"obstacle_flow_steps", static_cast<double>(ObstacleSteps(chosen, pick.step))});
    s.push_back({"obstacle_cleared_on_map", cleared ? 1.0 : 0.0});
    AddPathScores("avoid_", Normalised(ar, tn), demos, c.eval.resample, &s, {}, metres);
    s.push_back({"avoid_mcd", BodyDepth(chain, ar, cyl)});
    // One step of the composed system with the selected obstacle flow, on the configurations its
    // rollouts pass (every 10th; one thread; the median of 3 passes): the shipped flow's cost,
    // which `foresight bench` (a short synthetic obstacle flow) does not show.
    {
      std::vector<ArmVector> qs;
      for (const ArmPath& p : ar)
        for (Eigen::Index k = 0; k < p.joints.cols(); k += 10) qs.push_back(p.joints.col(k));
      auto ws = avoid.MakeWorkspace();
      ArmVector sink = ArmVector::Zero();
      const double seconds = bench::MedianSeconds(3, [&] {
        for (const ArmVector& q : qs) sink += avoid.Velocity(q, &ws);
      });
      (void)sink;
      s.push_back({"avoid_step_us",
                   1e6 * seconds / static_cast<double>(std::max<std::size_t>(1, qs.size()))});
    }

    if (eflow) {  // EFlow + a repulsor on every body point: q_dot = J^+ f - beta V_q(q)
      auto fws = field.MakeWorkspace();
      ChainData rdata = chain.MakeData();
      const auto point_field = [&](const Vec<3>& x, bool hess, OccupancyValue<3>* v) {
        field.Evaluate(x, fws.get(), hess, v);
      };
      const auto rep = [&](double beta) {
        return [&, beta](const ArmVector& q) -> ArmVector {
          ArmVector V;
          CSpacePotentialField(chain, q, point_field, &rdata, &V, nullptr);
          return PullBack(rdata, eflow_world(rdata.p_ee)) - beta * V;
        };
      };
      double gain = c.obstacle.repulsor_gains.back();
      bool rep_cleared = false;
      for (double beta : c.obstacle.repulsor_gains) {
        std::vector<ArmPath> rs;
        for (const ArmVector& q : train_starts)
          rs.push_back(RollOutArm(chain, rep(beta), q, goal, roll));
        if (AllReached(rs) && BodyMapProbability(chain, field, rs) < c.obstacle.clear_probability) {
          gain = beta;
          rep_cleared = true;
          break;
        }
      }
      std::vector<ArmPath> rr;
      for (const ArmVector& q : starts) rr.push_back(RollOutArm(chain, rep(gain), q, goal, roll));
      s.push_back({"eflow_repulsor_gain", gain});
      s.push_back({"eflow_repulsor_cleared_on_map", rep_cleared ? 1.0 : 0.0});
      AddPathScores("eflow_repulsor_", Normalised(rr, tn), demos, c.eval.resample, &s, {}, metres);
      s.push_back({"eflow_repulsor_mcd", BodyDepth(chain, rr, cyl)});
    }
    // Linear motion in C-space from each start configuration to the goal's (thesis baseline 7).
    std::vector<ArmPath> lines;
    for (const ArmVector& q0 : starts) {
      ArmVector qg;
      FS_THROW_UNLESS(InverseKinematics(chain, goal, q0, &qg, 1e-6, 500), demos.name,
                      ": the arm does not reach the goal ", goal.transpose());
      ArmPath p;
      p.joints.resize(kArmDof, c.eval.resample);
      p.end_effector.resize(3, c.eval.resample);
      ChainData d = chain.MakeData();
      for (int k = 0; k < c.eval.resample; ++k) {
        p.joints.col(k) = q0 + (qg - q0) * (k / (c.eval.resample - 1.0));
        Kinematics(chain, p.joints.col(k), &d);
        p.end_effector.col(k) = d.p_ee;
      }
      p.reached = true;
      lines.push_back(p);
    }
    AddPathScores("linear_", Normalised(lines, tn), demos, c.eval.resample, &s, {}, metres);
    s.push_back({"linear_mcd", BodyDepth(chain, lines, cyl)});
  }
  return s;
}

}  // namespace foresight::imitation
