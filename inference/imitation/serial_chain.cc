#include "inference/imitation/serial_chain.h"

#include <console_bridge/console.h>
#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <set>
#include <sstream>
#include <utility>

#include "core/error.h"
#include "inference/manipulation/urdf_util.h"

namespace foresight::imitation {
namespace {

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  FS_THROW_UNLESS(in.good(), "cannot read URDF file '", path, "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

using urdf_util::JointTypeName;
using urdf_util::ToIsometry;

/// Balls covering a cylinder (radius r, length L, axis a through c, in a link frame): n =
/// clamp(ceil(L / 2r), 1, 3) slices, each covered by the ball through its rim.
void CoverCylinder(const std::string& link, const Eigen::Vector3d& centre,
                   const Eigen::Vector3d& axis, double length, double radius,
                   std::vector<BodyPoint>* out) {
  const int n = std::clamp(static_cast<int>(std::ceil(length / (2 * radius) - 1e-9)), 1, 3);
  const double slice = length / n;
  const double ball = std::sqrt(radius * radius + 0.25 * slice * slice);
  for (int i = 0; i < n; ++i)
    out->push_back({link, centre + axis * (slice * (i + 0.5) - 0.5 * length), ball});
}

}  // namespace

SerialChain SerialChain::Load(const std::string& urdf_path, const std::string& base_link,
                              const std::string& tip_link, std::vector<BodyPoint> points) {
  return FromText(ReadWholeFile(urdf_path), urdf_path, base_link, tip_link, std::move(points));
}

SerialChain SerialChain::FromText(const std::string& urdf_text, const std::string& source,
                                  const std::string& base_link, const std::string& tip_link,
                                  std::vector<BodyPoint> points) {
  urdf::ModelInterfaceSharedPtr urdf;
  const urdf_util::FreeLinkCyclesOnExit free_cycles(urdf);  // a looped URDF must not leak
  urdf = urdf_util::ParseUrdf(urdf_text, source);
  SerialChain c;
  c.name_ = urdf->getName();
  c.base_link_ = base_link;
  c.tip_link_ = tip_link;
  for (const auto& name : {base_link, tip_link}) {
    if (urdf->getLink(name) == nullptr) {
      std::vector<std::string> names;
      for (const auto& [link_name, link] : urdf->links_) names.push_back(link_name);
      Fail(source, ": no link '", name, "' (links: ", Join(names), ")");
    }
  }
  // The path tip -> base through the parent joints.
  std::vector<urdf::JointConstSharedPtr> path;
  std::vector<std::string> links = {tip_link};
  std::set<std::string> seen = {tip_link};
  for (urdf::LinkConstSharedPtr link = urdf->getLink(tip_link); link->name != base_link;) {
    FS_THROW_UNLESS(link->parent_joint != nullptr, source, ": link '", base_link,
                    "' is not an ancestor of link '", tip_link, "' (the chain from '",
                    urdf->getRoot()->name, "' to the tip does not pass through it)");
    path.push_back(link->parent_joint);
    link = urdf->getLink(link->parent_joint->parent_link_name);
    // urdfdom accepts a loop of joints that is not connected to the root.
    FS_THROW_UNLESS(seen.insert(link->name).second, source, ": the parent joints above link '",
                    tip_link, "' form a loop through link '", link->name,
                    "' (expected a tree from the root)");
    links.push_back(link->name);
  }
  std::reverse(path.begin(), path.end());
  std::reverse(links.begin(), links.end());
  c.chain_links_ = links;

  // Walk base -> tip: X accumulates the constant transform from the current body to the link.
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  int body = 0;
  std::vector<std::pair<int, Eigen::Isometry3d>> link_in_body = {{0, X}};  // per chain link
  std::vector<std::string> arm_names;
  for (const auto& joint : path) {
    const std::string where = source + ": joint '" + joint->name + "'";
    X = X * ToIsometry(joint->parent_to_joint_origin_transform);
    if (joint->type != urdf::Joint::FIXED) {
      FS_THROW_UNLESS(
          joint->type == urdf::Joint::REVOLUTE || joint->type == urdf::Joint::CONTINUOUS, where,
          " is ", JointTypeName(joint->type),
          ": only revolute, continuous and fixed joints are supported on the chain");
      FS_THROW_UNLESS(joint->mimic == nullptr, where, " is a mimic joint: not supported");
      FS_THROW_UNLESS(body < kArmDof, where, " is arm joint ", body + 1, " from '", base_link,
                      "' to '", tip_link, "': expected exactly ", kArmDof,
                      " (found before it: ", Join(arm_names), ")");
      const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
      FS_THROW_UNLESS(axis.allFinite() && axis.norm() > 1e-12, where, " has a zero axis");
      const auto k = static_cast<size_t>(body);
      c.R_joint_[k] = X.linear();
      c.t_joint_[k] = X.translation();
      c.axis_[k] = axis.normalized();
      c.joint_names_[k] = joint->name;
      c.continuous_[k] = joint->type == urdf::Joint::CONTINUOUS;
      const urdf::JointLimits* limit = joint->limits.get();
      if (c.continuous_[k]) {
        const bool given = limit != nullptr && std::isfinite(limit->lower) &&
                           std::isfinite(limit->upper) && limit->lower < limit->upper;
        c.lower_[body] = given ? limit->lower : -std::numeric_limits<double>::infinity();
        c.upper_[body] = given ? limit->upper : std::numeric_limits<double>::infinity();
      } else {
        FS_THROW_UNLESS(limit != nullptr, where, " is revolute without <limit>");
        FS_THROW_UNLESS(std::isfinite(limit->lower) && std::isfinite(limit->upper) &&
                            limit->lower < limit->upper,
                        where, " <limit> needs finite lower < upper, got lower=", limit->lower,
                        " upper=", limit->upper);
        c.lower_[body] = limit->lower;
        c.upper_[body] = limit->upper;
      }
      arm_names.push_back(joint->name);
      ++body;
      X.setIdentity();
    }
    link_in_body.emplace_back(body, X);
  }
  FS_THROW_UNLESS(body == kArmDof, source, ": expected ", kArmDof,
                  " revolute or continuous joints from '", base_link, "' to '", tip_link,
                  "', found ", body, " (", Join(arm_names), ")");
  c.tip_body_ = link_in_body.back().first;
  c.tip_offset_ = link_in_body.back().second.translation();

  // Body points.
  c.points_ = std::move(points);
  const int n = c.num_points();
  c.point_body_.resize(static_cast<size_t>(n));
  c.point_offset_.resize(3, n);
  for (int j = 0; j < n; ++j) {
    const BodyPoint& point = c.points_[static_cast<size_t>(j)];
    const auto it = std::find(links.begin(), links.end(), point.link);
    FS_THROW_UNLESS(it != links.end(), source, ": body point ", j, " is on link '", point.link,
                    "', which is not on the chain (", Join(links), ")");
    FS_THROW_UNLESS(point.offset.allFinite() && std::isfinite(point.radius) && point.radius >= 0,
                    source, ": body point ", j, " on '", point.link,
                    "' needs a finite offset and radius >= 0, got offset (",
                    point.offset.transpose(), ") radius ", point.radius);
    const auto& [point_body, X_BL] = link_in_body[static_cast<size_t>(it - links.begin())];
    c.point_body_[static_cast<size_t>(j)] = point_body;
    c.point_offset_.col(j) = X_BL * point.offset;
  }
  return c;
}

std::vector<BodyPoint> SerialChain::JacoBodyPoints() {
  // The collision cylinders of j2n6s300.urdf (radius 0.025 m each): origin, axis and length in
  // the link frame (rpy (pi/2, 0, 0) turns the cylinder's z axis onto -y).
  constexpr double r = 0.025;
  std::vector<BodyPoint> points;
  CoverCylinder("j2n6s300_link_1", {0, 0, -0.06}, Eigen::Vector3d::UnitZ(), 0.06, r, &points);
  CoverCylinder("j2n6s300_link_2", {0, -0.21, 0}, -Eigen::Vector3d::UnitY(), 0.3, r, &points);
  CoverCylinder("j2n6s300_link_3", {0, 0.12, 0}, -Eigen::Vector3d::UnitY(), 0.17, r, &points);
  CoverCylinder("j2n6s300_link_4", {0, -0.01, -0.02}, Eigen::Vector3d::UnitZ(), 0.01, r, &points);
  CoverCylinder("j2n6s300_link_5", {0, 0, 0}, Eigen::Vector3d::UnitZ(), 0.01, r, &points);
  CoverCylinder("j2n6s300_link_6", {0, 0, 0}, Eigen::Vector3d::UnitZ(), 0.01, r, &points);
  points.push_back({"j2n6s300_end_effector", Eigen::Vector3d::Zero(), r});
  return points;
}

SerialChain SerialChain::LoadJaco(const std::string& jaco_dir) {
  const std::string path = jaco_dir + "/j2n6s300.urdf";
  const std::string text = ReadWholeFile(path);
  std::string base;
  {
    const urdf::ModelInterfaceSharedPtr urdf = urdf_util::ParseUrdf(text, path);
    const urdf_util::FreeLinkCyclesOnExit free_cycles(urdf);
    base = urdf->getLink("root") != nullptr ? "root" : urdf->getRoot()->name;
  }
  SerialChain chain = FromText(text, path, base, "j2n6s300_end_effector", JacoBodyPoints());
  for (int k = 0; k < kArmDof; ++k) {
    const std::string expected = "j2n6s300_joint_" + std::to_string(k + 1);
    FS_THROW_UNLESS(chain.joint_names_[static_cast<size_t>(k)] == expected, path, ": arm joint ",
                    k + 1, " is '", chain.joint_names_[static_cast<size_t>(k)], "', expected '",
                    expected, "'");
  }
  return chain;
}

ChainData SerialChain::MakeData() const {
  ChainData d;
  d.p.setZero(3, num_points());
  d.J.assign(points_.size(), PointJacobian6::Zero());
  d.z.setZero();
  d.o.setZero();
  d.R.fill(Eigen::Matrix3d::Identity());
  d.t.fill(Eigen::Vector3d::Zero());
  return d;
}

void Kinematics(const SerialChain& chain, const ArmVector& q, ChainData* d) {
  assert(d->p.cols() == chain.num_points() && d->J.size() == chain.points_.size());
  d->R[0].setIdentity();
  d->t[0].setZero();
  for (int k = 0; k < kArmDof; ++k) {
    const auto K = static_cast<size_t>(k);
    Eigen::Matrix3d R_WJ;  // joint frame in W
    R_WJ.noalias() = d->R[K] * chain.R_joint_[K];
    d->t[K + 1].noalias() = d->R[K] * chain.t_joint_[K];
    d->t[K + 1] += d->t[K];
    d->o.col(k) = d->t[K + 1];
    d->z.col(k).noalias() = R_WJ * chain.axis_[K];
    d->R[K + 1].noalias() = R_WJ * Eigen::AngleAxisd(q[k], chain.axis_[K]).toRotationMatrix();
  }
  const auto fill = [d](int body, const Eigen::Vector3d& offset, Eigen::Ref<Eigen::Vector3d> p,
                        PointJacobian6* J) {
    const auto B = static_cast<size_t>(body);
    p.noalias() = d->R[B] * offset;
    p += d->t[B];
    for (int i = 0; i < body; ++i) J->col(i) = d->z.col(i).cross(p - d->o.col(i));
    for (int i = body; i < kArmDof; ++i) J->col(i).setZero();
  };
  for (int j = 0; j < chain.num_points(); ++j)
    fill(chain.point_body_[static_cast<size_t>(j)], chain.point_offset_.col(j), d->p.col(j),
         &d->J[static_cast<size_t>(j)]);
  fill(chain.tip_body_, chain.tip_offset_, d->p_ee, &d->J_ee);
}

void AddPointPotential(const ChainData& d, int point, const Eigen::Vector3d& g,
                       const Eigen::Matrix3d& H, ArmVector* grad, ArmMatrix* hess) {
  const PointJacobian6& J = d.J[static_cast<size_t>(point)];
  grad->noalias() += J.transpose() * g;
  if (hess == nullptr) return;
  const Eigen::Matrix<double, 3, kArmDof> HJ = H * J;
  hess->noalias() += J.transpose() * HJ;
  // M_ik = g . (z_i x J_k) = (g x z_i) . J_k for i <= k.
  for (int i = 0; i < kArmDof; ++i) {
    const Eigen::Vector3d a = g.cross(d.z.col(i));
    (*hess)(i, i) += a.dot(J.col(i));
    for (int k = i + 1; k < kArmDof; ++k) {
      const double m = a.dot(J.col(k));
      (*hess)(i, k) += m;
      (*hess)(k, i) += m;
    }
  }
}

bool InverseKinematics(const SerialChain& chain, const Eigen::Vector3d& target,
                       const ArmVector& q_init, ArmVector* q, double tolerance,
                       int max_iterations) {
  FS_THROW_UNLESS(target.allFinite() && q_init.allFinite(),
                  "InverseKinematics: target and q_init must be finite, got target (",
                  target.transpose(), ") q_init (", q_init.transpose(), ")");
  FS_THROW_UNLESS(tolerance > 0 && max_iterations >= 0,
                  "InverseKinematics: needs tolerance > 0 and max_iterations >= 0, got ", tolerance,
                  " and ", max_iterations);
  constexpr double kDamping = 1e-2;  // m
  constexpr double kMaxStep = 0.5;   // rad
  ChainData data = chain.MakeData();
  *q = q_init.cwiseMax(chain.lower()).cwiseMin(chain.upper());
  for (int it = 0;; ++it) {
    Kinematics(chain, *q, &data);
    const Eigen::Vector3d e = target - data.p_ee;
    if (e.norm() <= tolerance) return true;
    if (it == max_iterations) return false;
    Eigen::Matrix3d A = data.J_ee * data.J_ee.transpose();
    A.diagonal().array() += kDamping * kDamping;
    ArmVector dq = data.J_ee.transpose() * A.partialPivLu().solve(e);
    const double step = dq.cwiseAbs().maxCoeff();
    if (step > kMaxStep) dq *= kMaxStep / step;
    *q = (*q + dq).cwiseMax(chain.lower()).cwiseMin(chain.upper());
  }
}

}  // namespace foresight::imitation
