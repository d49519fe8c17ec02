#include "inference/imitation/cspace.h"

#include <Eigen/LU>
#include <cmath>
#include <utility>
#include <vector>

#include "core/error.h"

namespace foresight::imitation {

// ---- CSpaceObstacleTransform ----------------------------------------------------------------

CSpaceObstacleTransform::CSpaceObstacleTransform(SerialChain chain, OccupancyField<3> field,
                                                 FlowSettings<kArmDof> settings, GoalGate gate)
    : chain_(std::move(chain)), field_(std::move(field)), settings_(settings), gate_(gate) {
  FS_THROW_UNLESS(std::isfinite(settings_.time) && settings_.time > 0,
                  "C-space obstacle transform: flow time must be finite and > 0, got ",
                  settings_.time);
  FS_THROW_UNLESS(settings_.steps >= 1, "C-space obstacle transform: steps must be >= 1, got ",
                  settings_.steps);
  FS_THROW_UNLESS(chain_.num_points() > 0, "C-space obstacle transform: chain '", chain_.name(),
                  "' has no body points");
  FS_THROW_UNLESS(field_.grid().size() > 0,
                  "C-space obstacle transform: the occupancy field is empty");
  FS_THROW_UNLESS(gate_.goal.allFinite() && std::isfinite(gate_.length) && gate_.length >= 0,
                  "C-space obstacle transform: the goal gate needs a finite goal and length >= 0, "
                  "got goal (",
                  gate_.goal.transpose(), ") length ", gate_.length);
}

CSpaceTransformWorkspace CSpaceObstacleTransform::MakeWorkspace() const {
  return {chain_.MakeData(), field_.MakeWorkspace()};
}

ArmVector CSpaceObstacleTransform::Field(const ArmVector& q, CSpaceTransformWorkspace* ws,
                                         ArmMatrix* jacobian, double* occupancy) const {
  RbfFeatures<3>* features = ws->features.get();
  const auto at_point = [this, features](const Vec<3>& x, bool with_hessian,
                                         OccupancyValue<3>* value) {
    field_.Evaluate(x, features, with_hessian, value);
  };
  ArmVector V;
  const double total = CSpacePotentialField(chain_, q, at_point, &ws->chain, &V, jacobian);
  if (occupancy != nullptr) *occupancy = total;
  if (gate_.length > 0) {    // w V_q, d(w V_q) = w dV_q + V_q grad_q w' (file comment)
    Eigen::Vector3d grad_x;  // dw / dx_ee; grad_q w = J_ee' grad_x
    const double w = gate_.Weight(ws->chain.p_ee, &grad_x);
    if (jacobian != nullptr) {
      const ArmVector grad_w = ws->chain.J_ee.transpose() * grad_x;
      *jacobian = w * *jacobian + V * grad_w.transpose();
    }
    V *= w;
  }
  return V;
}

ArmVector CSpaceObstacleTransform::Forward(const ArmVector& p, CSpaceTransformWorkspace* ws,
                                           ArmMatrix* jacobian) const {
  const double h = settings_.time / settings_.steps;
  ArmVector q = p;
  if (jacobian != nullptr) jacobian->setIdentity();
  ArmMatrix dV, step;
  for (int k = 0; k < settings_.steps; ++k) {
    const ArmVector V = Field(q, ws, jacobian != nullptr ? &dV : nullptr);
    // Where V_q (and, when asked, dV_q) is exactly zero, e.g. no body point within the map's
    // support or the gate closed, q and J_o would stay as they are for every remaining step (V_q
    // is autonomous): stopping gives the same values (up to the sign of a zero).
    if (V.isZero(0) && (jacobian == nullptr || dV.isZero(0))) break;
    if (jacobian != nullptr) {
      step = h * dV;
      step.diagonal().array() += 1;
      *jacobian = step * *jacobian;  // fixed size: the product is evaluated on the stack
    }
    q += h * V;
  }
  return q;
}

bool CSpaceObstacleTransform::Inverse(const ArmVector& q, CSpaceTransformWorkspace* ws,
                                      ArmVector* p, double tolerance, int max_iterations) const {
  const double h = settings_.time / settings_.steps;
  ArmVector next = q;  // q_{k+1}
  for (int k = settings_.steps - 1; k >= 0; --k) {
    ArmVector x = next - h * Field(next, ws);
    bool converged = false;
    for (int it = 0; it < max_iterations && x.allFinite(); ++it) {
      const ArmVector x_new = next - h * Field(x, ws);
      const double change = (x_new - x).cwiseAbs().maxCoeff();
      x = x_new;
      if (change <= tolerance) {
        converged = true;
        break;
      }
    }
    if (!converged || !x.allFinite()) return false;
    next = x;
  }
  *p = next;
  return true;
}

// ---- CSpaceSystem ----------------------------------------------------------------------------

CSpaceSystem::CSpaceSystem(SerialChain chain, ImitationSystem<3> imitation,
                           TaskNormalisation normalisation,
                           std::optional<CSpaceObstacleTransform> obstacle, double damping)
    : chain_(std::move(chain)),
      imitation_(std::move(imitation)),
      normalisation_(normalisation),
      obstacle_(std::move(obstacle)),
      damping_(damping) {
  FS_THROW_UNLESS(normalisation_.offset.allFinite() && std::isfinite(normalisation_.scale) &&
                      normalisation_.scale > 0,
                  "C-space system: normalisation needs a finite offset and scale > 0, got offset (",
                  normalisation_.offset.transpose(), ") scale ", normalisation_.scale);
  FS_THROW_UNLESS(std::isfinite(damping_) && damping_ >= 0,
                  "C-space system: damping must be finite and >= 0, got ", damping_);
  if (obstacle_) {
    const SerialChain& other = obstacle_->chain();
    for (int k = 0; k < kArmDof; ++k)
      FS_THROW_UNLESS(other.joint_names()[static_cast<size_t>(k)] ==
                          chain_.joint_names()[static_cast<size_t>(k)],
                      "C-space system: the obstacle transform's arm joint ", k + 1, " is '",
                      other.joint_names()[static_cast<size_t>(k)], "', the system's is '",
                      chain_.joint_names()[static_cast<size_t>(k)], "' (not the same arm)");
  }
}

CSpaceSystemWorkspace CSpaceSystem::MakeWorkspace() const {
  CSpaceSystemWorkspace ws;
  ws.chain = chain_.MakeData();
  ws.imitation = imitation_.flow().MakeWorkspace();
  if (obstacle_) ws.obstacle = obstacle_->MakeWorkspace();
  return ws;
}

Eigen::Vector3d CSpaceSystem::TaskVelocity(const Eigen::Vector3d& x,
                                           CSpaceSystemWorkspace* ws) const {
  return imitation_.Velocity(normalisation_.ToModel(x), &ws->imitation) / normalisation_.scale;
}

ArmVector CSpaceSystem::InnerVelocity(const ArmVector& q, CSpaceSystemWorkspace* ws) const {
  Kinematics(chain_, q, &ws->chain);
  const PointJacobian6& J = ws->chain.J_ee;
  const Eigen::Vector3d f = TaskVelocity(ws->chain.p_ee, ws);
  Eigen::Matrix3d A = J * J.transpose();
  A.diagonal().array() += damping_ * damping_;
  return J.transpose() * A.partialPivLu().solve(f);
}

ArmVector CSpaceSystem::Velocity(const ArmVector& p, CSpaceSystemWorkspace* ws) const {
  if (!obstacle_) return InnerVelocity(p, ws);
  ArmMatrix J_o;
  const ArmVector q = obstacle_->Forward(p, &ws->obstacle, &J_o);
  return J_o.partialPivLu().solve(InnerVelocity(q, ws));
}

ArmVector CSpaceSystem::Inner(const ArmVector& p, CSpaceSystemWorkspace* ws) const {
  return obstacle_ ? obstacle_->Forward(p, &ws->obstacle) : p;
}

// ---- rollout -----------------------------------------------------------------------------------

const char* CSpaceStopName(CSpaceStop stop) {
  switch (stop) {
    case CSpaceStop::kReached:
      return "reached";
    case CSpaceStop::kMaxSteps:
      return "max_steps";
    case CSpaceStop::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

CSpaceRollout RollOutCSpace(const CSpaceSystem& system, const ArmVector& start,
                            const RolloutSettings& settings) {
  FS_THROW_UNLESS(start.allFinite(), "C-space rollout: start must be finite, got (",
                  start.transpose(), ")");
  FS_THROW_UNLESS(std::isfinite(settings.dt) && settings.dt > 0 && settings.max_steps >= 0 &&
                      settings.goal_tolerance >= 0,
                  "C-space rollout: needs dt > 0, max_steps >= 0 and goal_tolerance >= 0, got dt ",
                  settings.dt, ", max_steps ", settings.max_steps, ", goal_tolerance ",
                  settings.goal_tolerance);
  CSpaceSystemWorkspace ws = system.MakeWorkspace();
  ChainData chain = system.chain().MakeData();
  const Eigen::Vector3d goal = system.goal();
  std::vector<ArmVector> joints;
  std::vector<Eigen::Vector3d> end_effector;
  CSpaceRollout out;
  ArmVector p = start;
  for (int step = 0;; ++step) {
    Kinematics(system.chain(), p, &chain);
    joints.push_back(p);
    end_effector.push_back(chain.p_ee);
    if ((chain.p_ee - goal).norm() <= settings.goal_tolerance) {
      out.stop = CSpaceStop::kReached;
      break;
    }
    if (step == settings.max_steps) {
      out.stop = CSpaceStop::kMaxSteps;
      break;
    }
    const ArmVector v = system.Velocity(p, &ws);
    if (!v.allFinite()) {
      out.stop = CSpaceStop::kNonFinite;
      break;
    }
    ArmVector dp = settings.dt * v;  // max_step_length: the largest joint step (rad, max norm)
    const double length = dp.cwiseAbs().maxCoeff();
    if (settings.max_step_length > 0 && length > settings.max_step_length)
      dp *= settings.max_step_length / length;
    p += dp;
  }
  const auto n = static_cast<Eigen::Index>(joints.size());
  out.joints.resize(kArmDof, n);
  out.end_effector.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    out.joints.col(i) = joints[static_cast<size_t>(i)];
    out.end_effector.col(i) = end_effector[static_cast<size_t>(i)];
  }
  return out;
}

}  // namespace foresight::imitation
