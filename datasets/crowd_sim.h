#pragma once
/// The force-based power-law crowd model (Karamouzas, Skinner, Guy, "Universal power law governing
/// pedestrian interactions", PRL 113, 238701, 2014) and a reader of the scenario files of the
/// "Implicit Crowds" reference code (../shared/data/crowd_scenarios_implicit_crowds/README.md).
///
/// Each pedestrian i (unit mass) feels
///   goal force     (v_pref * unit(g_i - x_i) - v_i) / relaxation
///   interactions   -grad_{x_i} E(tau_ij),  E(tau) = k tau^-m exp(-tau/tau0)   (PRL eq. 1; m =
///   exponent)
/// where tau_ij is the time to collision of the discs i and j under constant velocities; other
/// pedestrians and the robot count as neighbours within neighbor_dist. Walls (and the extent's
/// border) interact through the same energy on the time to collision with the thick segment (scale
/// wall_k) and are never penetrated (positions are projected out, the inward velocity removed).
/// Accelerations are capped at max_accel, speeds at max_speed; semi-implicit Euler substeps.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/geometry2d.h"
#include "datasets/crowd_scenario.h"

namespace foresight {

/// Time to collision of two discs with relative position x = x_i - x_j, relative velocity
/// v = v_i - v_j and summed radius r (m): the smallest t >= 0 with |x + v t| = r, or +inf when they
/// never touch. Overlapping discs (|x| < r) that approach give 0.
double TimeToCollision(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r);

/// E(tau) = k tau^-m exp(-tau/tau0) (PRL 2014 eq. 1); 0 for tau = inf.
double PowerLawEnergy(double tau, double k, double exponent, double tau0);

/// -grad_x E(tau(x, v, r)) on agent i for relative position x = x_i - x_j and velocity v = v_i -
/// v_j (the force of the PRL reference code). With a = v.v, b = x.v, c = x.x - r^2, d = b^2 - a c
/// and tau = (-b - sqrt d)/a:  grad_x tau = -(v + (b v - a x)/sqrt d)/a,  dE/dtau = -E (m/tau +
/// 1/tau0). Zero when there is no future collision. Overlapping discs use the effective radius 0.99
/// |x| (as the reference code) so that approaching overlaps are pushed apart; tau is clamped below
/// at tau_min (the force magnitude then is that at tau_min).
Eigen::Vector2d PowerLawInteractionForce(const Eigen::Vector2d& x, const Eigen::Vector2d& v,
                                         double r, double k, const PowerLawParams& p);

/// A wall for the simulator: segment p-q thickened by half_thickness on each side.
struct SimWall {
  Eigen::Vector2d p, q;
  double half_thickness = 0;
};

/// Time to collision of a disc (centre x, velocity v, radius r) with a static thick segment, or
/// +inf.
double WallTimeToCollision(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r,
                           const SimWall& w);
/// -grad_x of wall_k tau^-m exp(-tau/tau0) for the wall time to collision (zero without collision).
Eigen::Vector2d WallInteractionForce(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r,
                                     const SimWall& w, const PowerLawParams& p);

/// The simulator's walls of a scenario: its wall segments plus the four sides of the extent (zero
/// thickness).
std::vector<SimWall> ScenarioWalls(const CrowdScenarioConfig& scenario);

/// A simulated power-law crowd. Deterministic in (scenario, seed).
class PowerLawCrowd : public Crowd {
 public:
  /// Spawns every group's pedestrians uniformly in its spawn box, without overlap with each other,
  /// the walls or the robot's start; throws foresight::Error when a box cannot hold its group.
  PowerLawCrowd(const CrowdScenarioConfig& scenario, std::uint64_t seed);

  void Step(double dt, const RobotAgent& robot) override;
  double time() const override { return time_; }
  const std::vector<CrowdAgent>& agents() const override { return agents_; }

  /// The current target of pedestrian i (m).
  const Eigen::Vector2d& target(int i) const { return state_[i].target; }
  /// Whether pedestrian i (not round-trip) has reached its goal (within goal_tolerance()).
  bool arrived(int i) const { return state_[i].arrived; }
  /// The preferred speed drawn for pedestrian i (m/s, capped at max_speed).
  double preferred_speed(int i) const { return state_[i].preferred_speed; }
  /// Distance to the target under which it counts as reached (m).
  static constexpr double goal_tolerance() { return 0.3; }

  /// The accelerations (m/s^2, before the max_accel cap) on every pedestrian now.
  std::vector<Eigen::Vector2d> Accelerations(const RobotAgent& robot) const;

 private:
  struct State {
    int group = 0;
    double preferred_speed = 1.0;
    Eigen::Vector2d target = Eigen::Vector2d::Zero();
    bool to_goal = true;   ///< round trips: heading to the goal box (else back to the spawn box)
    bool arrived = false;  ///< one-way pedestrians at their goal
  };
  void Substep(double h, const RobotAgent& robot);
  void ComputeAccelerations(const RobotAgent& robot, std::vector<Eigen::Vector2d>* accel) const;
  Eigen::Vector2d SampleBox(const std::vector<double>& box);

  CrowdScenarioConfig scenario_;
  std::vector<SimWall> walls_;
  std::vector<CrowdAgent> agents_;
  std::vector<State> state_;
  std::vector<Eigen::Vector2d> accel_;  // work buffer
  std::mt19937_64 rng_;
  double time_ = 0;
};

/// Reads an Implicit Crowds scenario (`xmin xmax`, `ymin ymax`, `N`, then N lines
/// `gid x y goal_x goal_y pref_speed radius`) into a simulated scenario: one one-way group per
/// agent (degenerate spawn and goal boxes, no speed jitter, the agent's radius), the file's bounds
/// as the extent, no walls, the PRL 2014 default parameters (PowerLawParams{}) with max_speed
/// raised to 1.5 x the largest preferred speed. The files contain no robot: robot start and goal
/// are put at the extent's lower-left and upper-right corners (1 m inside); run them with
/// RobotAgent::present = false. Malformed files are Errors naming file and line.
CrowdScenarioConfig ReadImplicitCrowdsScenario(const std::string& path);

/// Applies an Implicit Crowds `implicit.ini` (key=value) to `base`: k -> k, p -> exponent,
/// t0 -> tau0, neighborDist -> neighbor_dist. `ksi` there is a weight of the implicit objective,
/// not the PRL relaxation time, and is ignored, as are the optimiser keys. Unknown keys are Errors.
PowerLawParams ReadImplicitCrowdsParameters(const std::string& path, PowerLawParams base);

}  // namespace foresight
