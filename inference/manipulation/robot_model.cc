#include "inference/manipulation/robot_model.h"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <utility>

#include "core/error.h"
#include "inference/manipulation/urdf_util.h"

namespace foresight::manipulation {
namespace {

// ---- loading helpers ------------------------------------------------------------------------

std::string ReadWholeFile(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  FS_THROW_UNLESS(in.good(), "cannot read ", what, " file '", path, "'");
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

/// A field of a CSV row as a finite double; throws naming file:line and the column.
double ParseNumber(const std::string& field, const std::string& column, const std::string& where) {
  const char* begin = field.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  FS_THROW_UNLESS(!field.empty() && end == begin + field.size() && std::isfinite(value), where,
                  ": ", column, " '", field, "' is not a finite number");
  return value;
}

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

struct SphereRow {
  std::string link;
  Eigen::Vector3d p_LS;
  double radius;
  std::string where;  // file:line
};

/// Rows of a `link,x,y,z,radius` text (header first; blank and '#' lines skipped); `name` (a path)
/// prefixes the messages.
std::vector<SphereRow> ReadSpheres(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::vector<SphereRow> rows;
  bool header = false;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = Trim(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = name + ":" + std::to_string(number);
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(Trim(field));
    if (!line.empty() && line.back() == ',') fields.push_back("");
    if (!header) {
      FS_THROW_UNLESS(Join(fields) == "link, x, y, z, radius", where,
                      ": expected the header 'link,x,y,z,radius', got '", line, "'");
      header = true;
      continue;
    }
    FS_THROW_UNLESS(fields.size() == 5, where,
                    ": expected 5 comma-separated fields link,x,y,z,radius, got ", fields.size(),
                    ": '", line, "'");
    SphereRow row;
    row.link = fields[0];
    FS_THROW_UNLESS(!row.link.empty(), where, ": empty link name");
    row.p_LS << ParseNumber(fields[1], "x", where), ParseNumber(fields[2], "y", where),
        ParseNumber(fields[3], "z", where);
    row.radius = ParseNumber(fields[4], "radius", where);
    FS_THROW_UNLESS(row.radius > 0, where, ": radius must be > 0, got ", row.radius);
    row.where = where;
    rows.push_back(row);
  }
  FS_THROW_UNLESS(!rows.empty(), name, ": no sphere rows (expected header 'link,x,y,z,radius' ",
                  "and one row per sphere)");
  return rows;
}

struct DisabledPair {
  std::string link1, link2, where;  // where: file:line
};

/// <disable_collisions link1 link2> entries of an SRDF text; `name` (a path) prefixes the messages.
std::vector<DisabledPair> ReadDisabledPairs(const std::string& text, const std::string& name) {
  urdf_util::CheckUtf8(text, name);
  TiXmlDocument doc;
  doc.Parse(text.c_str());
  if (doc.Error())
    Fail(name, ":", doc.ErrorRow(), ":", doc.ErrorCol(), ": not valid XML: ", doc.ErrorDesc());
  const TiXmlElement* robot = doc.RootElement();
  FS_THROW_UNLESS(robot != nullptr && robot->ValueStr() == "robot", name,
                  ": the root element must be <robot>");
  std::vector<DisabledPair> pairs;
  for (const TiXmlElement* e = robot->FirstChildElement("disable_collisions"); e != nullptr;
       e = e->NextSiblingElement("disable_collisions")) {
    const std::string where = name + ":" + std::to_string(e->Row());
    const char* link1 = e->Attribute("link1");
    const char* link2 = e->Attribute("link2");
    FS_THROW_UNLESS(link1 != nullptr && link2 != nullptr, where,
                    ": <disable_collisions> needs attributes link1 and link2");
    pairs.push_back({link1, link2, where});
  }
  return pairs;
}

// ---- kinematics helpers ---------------------------------------------------------------------

/// [3 x 3] cross-product matrix: Skew(a) b = a x b.
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d S;
  S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return S;
}

/// Jacobian (J, [3 x kDof] column-major), velocity and Jdot qdot (v_Jdot = [v; Jdot qdot]) of the
/// point p_W on body B from the affine maps; columns of joints B.. are zero. Fixed sizes: the
/// compiler unrolls and vectorises each body's kernel.
template <int B>
inline void PointKernel(const KinematicsData::Affine& f, const Eigen::Vector3d& p_W, double* J_out,
                        double* v_out, double* Jdot_qdot_out) {
  if constexpr (B > 0) {
    Eigen::Map<Eigen::Matrix<double, 3 * B, 1>> J(J_out);
    J = f.G.template topRows<3 * B>() * p_W + f.g.template head<3 * B>();
  }
  if constexpr (B < kDof) {
    Eigen::Map<Eigen::Matrix<double, 3 * (kDof - B), 1>> zero_columns(J_out + 3 * B);
    zero_columns.setZero();
  }
  const Eigen::Matrix<double, 6, 1> v_a = f.K[B] * p_W + f.k[B];
  Eigen::Map<Eigen::Vector3d> v(v_out), Jdot_qdot(Jdot_qdot_out);
  v = v_a.head<3>();
  Jdot_qdot = v_a.tail<3>();
}

template <int B>
void SpheresOnBody(const std::vector<int>& spheres, KinematicsData* d) {
  for (const int s : spheres) {
    const auto S = static_cast<size_t>(s);
    PointKernel<B>(d->affine, d->p_WS.col(s), d->J_WS[S].data(), d->v_WS.col(s).data(),
                   d->Jdot_qdot_WS[S].data());
  }
}

template <size_t... B>
void AllSpheres(const std::array<std::vector<int>, kDof + 1>& spheres_on_body, KinematicsData* d,
                std::index_sequence<B...>) {
  (SpheresOnBody<static_cast<int>(B)>(spheres_on_body[B], d), ...);
}

template <size_t... B>
void EndEffector(int body, KinematicsData* d, std::index_sequence<B...>) {
  ((body == static_cast<int>(B)
        ? PointKernel<static_cast<int>(B)>(d->affine, d->p_WE, d->J_WE.data(), d->v_WE.data(),
                                           d->Jdot_qdot_WE.data())
        : void()),
   ...);
}

}  // namespace

// ---- RobotModel -------------------------------------------------------------------------------

RobotModel RobotModel::Load(const std::string& urdf_path, const std::string& spheres_csv,
                            const std::string& srdf_path) {
  const std::string urdf = ReadWholeFile(urdf_path, "URDF");
  const std::string spheres = ReadWholeFile(spheres_csv, "spheres");
  const std::string srdf = srdf_path.empty() ? "" : ReadWholeFile(srdf_path, "SRDF");
  return FromTexts(urdf, urdf_path, spheres, spheres_csv, srdf_path.empty() ? nullptr : &srdf,
                   srdf_path);
}

RobotModel RobotModel::FromText(const std::string& urdf, const std::string& spheres_csv,
                                const std::string& srdf, const std::string& source) {
  return FromTexts(urdf, source + " URDF", spheres_csv, source + " spheres",
                   srdf.empty() ? nullptr : &srdf, source + " SRDF");
}

RobotModel RobotModel::FromTexts(const std::string& urdf_text, const std::string& urdf_name,
                                 const std::string& spheres_text, const std::string& spheres_name,
                                 const std::string* srdf_text, const std::string& srdf_name) {
  RobotModel m;

  // Kinematic tree (urdfdom), depth first from the root so parents precede children.
  urdf::ModelInterfaceSharedPtr urdf;
  const urdf_util::FreeLinkCyclesOnExit free_cycles(urdf);  // a looped URDF must not leak
  urdf = urdf_util::ParseUrdf(urdf_text, urdf_name);
  FS_THROW_UNLESS(urdf->getRoot() != nullptr, urdf_name, ": no root link");
  m.name_ = urdf->getName();
  std::vector<Eigen::Isometry3d> X_BJ;
  std::vector<Eigen::Vector3d> axes;
  std::vector<urdf::JointConstSharedPtr> arm_joints;
  int last_arm_child = -1;
  std::vector<std::pair<urdf::LinkConstSharedPtr, int>> stack = {{urdf->getRoot(), -1}};
  while (!stack.empty()) {
    const auto [link, parent] = stack.back();
    stack.pop_back();
    const int index = static_cast<int>(m.link_names_.size());
    int body = 0;
    Eigen::Isometry3d X_BL = Eigen::Isometry3d::Identity();
    if (parent >= 0) {
      const urdf::JointConstSharedPtr joint = link->parent_joint;
      const auto p = static_cast<size_t>(parent);
      const Eigen::Isometry3d X_BJ0 =
          m.X_BL_[p] * ToIsometry(joint->parent_to_joint_origin_transform);
      if (joint->type == urdf::Joint::FIXED) {
        body = m.link_body_[p];
        X_BL = X_BJ0;
      } else {
        const std::string where = urdf_name + ": joint '" + joint->name + "'";
        FS_THROW_UNLESS(joint->type == urdf::Joint::REVOLUTE, where, " is ",
                        JointTypeName(joint->type),
                        ": only revolute arm joints and fixed joints are supported (fingers "
                        "must be fixed joints)");
        FS_THROW_UNLESS(joint->mimic == nullptr, where,
                        " is a mimic joint: only independent revolute arm joints are supported");
        FS_THROW_UNLESS(m.link_body_[p] == static_cast<int>(arm_joints.size()), where,
                        " is not on the chain after '",
                        arm_joints.empty() ? std::string("the root") : arm_joints.back()->name,
                        "': the non-fixed joints must form one serial chain from the root");
        const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
        FS_THROW_UNLESS(axis.allFinite() && axis.norm() > 1e-12, where, " has a zero axis");
        FS_THROW_UNLESS(joint->limits != nullptr, where, " has no <limit>");
        arm_joints.push_back(joint);
        X_BJ.push_back(X_BJ0);
        axes.push_back(axis.normalized());
        body = static_cast<int>(arm_joints.size());
        last_arm_child = index;
      }
    }
    m.link_names_.push_back(link->name);
    m.link_parent_.push_back(parent);
    m.link_body_.push_back(body);
    m.X_BL_.push_back(X_BL);
    for (auto it = link->child_links.rbegin(); it != link->child_links.rend(); ++it)
      stack.emplace_back(*it, index);
  }
  {
    std::vector<std::string> names;
    for (const auto& joint : arm_joints) names.push_back(joint->name);
    FS_THROW_UNLESS(arm_joints.size() == static_cast<size_t>(kDof), urdf_name, ": expected ", kDof,
                    " revolute arm joints, found ", arm_joints.size(), " (", Join(names), ")");
    m.joint_names_ = names;
  }
  for (int k = 0; k < kDof; ++k) {
    const urdf::Joint& joint = *arm_joints[static_cast<size_t>(k)];
    const urdf::JointLimits& limit = *joint.limits;
    const std::string where = urdf_name + ": joint '" + joint.name + "' <limit>";
    FS_THROW_UNLESS(
        std::isfinite(limit.lower) && std::isfinite(limit.upper) && limit.lower < limit.upper,
        where, " needs lower < upper, got lower=", limit.lower, " upper=", limit.upper);
    FS_THROW_UNLESS(std::isfinite(limit.velocity) && limit.velocity > 0, where,
                    " needs velocity > 0, got ", limit.velocity);
    m.limits_.lower[k] = limit.lower;
    m.limits_.upper[k] = limit.upper;
    m.limits_.velocity[k] = limit.velocity;
    m.limits_.soft_lower[k] = limit.lower;
    m.limits_.soft_upper[k] = limit.upper;
    if (joint.safety) {
      const double lo = joint.safety->soft_lower_limit, hi = joint.safety->soft_upper_limit;
      FS_THROW_UNLESS(std::isfinite(lo) && std::isfinite(hi) && lo < hi, urdf_name, ": joint '",
                      joint.name, "' <safety_controller> needs soft_lower_limit < ",
                      "soft_upper_limit, got ", lo, " and ", hi);
      m.limits_.soft_lower[k] = lo;
      m.limits_.soft_upper[k] = hi;
    }
  }
  // Turn each body frame so that its joint axis is z, making the joint rotation Rz(q): body k+1
  // is J_k R(a_k, q) = (J_k R_k) Rz(q) R_k^T with R_k e_z = a_k, and the constant R_k^T moves into
  // the poses of the next joint and of the links on body k+1.
  std::array<Eigen::Matrix3d, kDof> R_axis;
  for (size_t k = 0; k < static_cast<size_t>(kDof); ++k) {
    R_axis[k] = axes[k] == Eigen::Vector3d::UnitZ()
                    ? Eigen::Matrix3d::Identity()
                    : Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axes[k])
                          .toRotationMatrix();
    const auto untwist = [&](size_t body, const Eigen::Isometry3d& X) {
      if (body == 0) return X;
      Eigen::Isometry3d out = X;
      out.linear() = R_axis[body - 1].transpose() * X.linear();
      out.translation() = R_axis[body - 1].transpose() * X.translation();
      return out;
    };
    m.X_BJ_[k] = untwist(k, X_BJ[k]);
    m.X_BJ_[k].linear() = m.X_BJ_[k].linear() * R_axis[k];
  }
  for (size_t l = 0; l < m.X_BL_.size(); ++l) {
    const auto body = static_cast<size_t>(m.link_body_[l]);
    if (body == 0) continue;
    m.X_BL_[l].translation() = R_axis[body - 1].transpose() * m.X_BL_[l].translation();
    m.X_BL_[l].linear() = R_axis[body - 1].transpose() * m.X_BL_[l].linear();
  }
  const auto grasp = std::find(m.link_names_.begin(), m.link_names_.end(), "panda_grasptarget");
  m.ee_link_ = grasp != m.link_names_.end() ? static_cast<int>(grasp - m.link_names_.begin())
                                            : last_arm_child;
  m.ee_body_ = m.link_body_[static_cast<size_t>(m.ee_link_)];
  m.p_BE_ = m.X_BL_[static_cast<size_t>(m.ee_link_)].translation();

  // Collision spheres.
  const auto find_link = [&m](const std::string& name) {
    const auto it = std::find(m.link_names_.begin(), m.link_names_.end(), name);
    return it == m.link_names_.end() ? -1 : static_cast<int>(it - m.link_names_.begin());
  };
  for (const SphereRow& row : ReadSpheres(spheres_text, spheres_name)) {
    const int link = find_link(row.link);
    FS_THROW_UNLESS(link >= 0, row.where, ": unknown link '", row.link, "' (", urdf_name,
                    " has: ", Join(m.link_names_), ")");
    m.spheres_.push_back({link, row.link, row.p_LS, row.radius});
  }
  const int n = m.num_spheres();
  m.sphere_body_.resize(static_cast<size_t>(n));
  m.p_BS_.resize(3, n);
  for (int s = 0; s < n; ++s) {
    const auto link = static_cast<size_t>(m.spheres_[static_cast<size_t>(s)].link);
    m.sphere_body_[static_cast<size_t>(s)] = m.link_body_[link];
    m.spheres_on_body_[static_cast<size_t>(m.link_body_[link])].push_back(s);
    m.p_BS_.col(s) = m.X_BL_[link] * m.spheres_[static_cast<size_t>(s)].p_LS;
  }

  // Disabled link pairs (SRDF) and the self-collision sphere pairs.
  const auto num_links = static_cast<size_t>(m.num_links());
  m.disabled_.assign(num_links * num_links, 0);
  if (srdf_text != nullptr) {
    for (const DisabledPair& entry : ReadDisabledPairs(*srdf_text, srdf_name)) {
      const int a = find_link(entry.link1), b = find_link(entry.link2);
      for (const auto& [id, name] : {std::pair{a, entry.link1}, std::pair{b, entry.link2}})
        FS_THROW_UNLESS(id >= 0, entry.where, ": <disable_collisions> names unknown link '", name,
                        "' (", urdf_name, " has: ", Join(m.link_names_), ")");
      m.disabled_[static_cast<size_t>(a) * num_links + static_cast<size_t>(b)] = 1;
      m.disabled_[static_cast<size_t>(b) * num_links + static_cast<size_t>(a)] = 1;
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const int la = m.spheres_[static_cast<size_t>(i)].link;
      const int lb = m.spheres_[static_cast<size_t>(j)].link;
      const int body_a = m.link_body_[static_cast<size_t>(la)];
      const int body_b = m.link_body_[static_cast<size_t>(lb)];
      if (std::abs(body_a - body_b) <= 1 || m.CollisionDisabled(la, lb)) continue;
      m.self_collision_pairs_.emplace_back(i, j);
    }
  }
  return m;
}

RobotModel RobotModel::LoadPanda(const std::string& franka_dir) {
  RobotModel m = Load(franka_dir + "/panda.urdf", franka_dir + "/spheres_vamp.csv",
                      franka_dir + "/panda.srdf");
  for (int k = 0; k < kDof; ++k) {
    const std::string expected = "panda_joint" + std::to_string(k + 1);
    FS_THROW_UNLESS(m.joint_names_[static_cast<size_t>(k)] == expected, franka_dir,
                    "/panda.urdf: arm joint ", k + 1, " is '",
                    m.joint_names_[static_cast<size_t>(k)], "', expected '", expected, "'");
  }
  return m;
}

int RobotModel::LinkIndex(const std::string& name) const {
  const auto it = std::find(link_names_.begin(), link_names_.end(), name);
  FS_THROW_UNLESS(it != link_names_.end(), "robot '", name_, "' has no link '", name,
                  "' (links: ", Join(link_names_), ")");
  return static_cast<int>(it - link_names_.begin());
}

bool RobotModel::CollisionDisabled(int link_a, int link_b) const {
  return disabled_[static_cast<size_t>(link_a) * link_names_.size() +
                   static_cast<size_t>(link_b)] != 0;
}

KinematicsData RobotModel::MakeData() const {
  KinematicsData d;
  const int n = num_spheres();
  d.X_WL.assign(link_names_.size(), Eigen::Isometry3d::Identity());
  d.p_WS.setZero(3, n);
  d.v_WS.setZero(3, n);
  d.J_WS.assign(static_cast<size_t>(n), PointJacobian::Zero());
  d.Jdot_qdot_WS.assign(static_cast<size_t>(n), Eigen::Vector3d::Zero());
  d.X_WB.fill(Eigen::Isometry3d::Identity());
  d.z_WJ.fill(Eigen::Vector3d::UnitZ());
  d.p_WJ.fill(Eigen::Vector3d::Zero());
  for (auto* field : {&d.w_WB, &d.alpha_WB, &d.v_WB, &d.a_WB}) field->fill(Eigen::Vector3d::Zero());
  return d;
}

// ---- kinematics -------------------------------------------------------------------------------

void ForwardKinematics(const RobotModel& model, const JointVector& q, KinematicsData* d) {
  assert(d->X_WL.size() == model.link_names_.size() && d->p_WS.cols() == model.num_spheres());
  // Bodies: body k+1 is joint k's (z-aligned) frame rotated by Rz(q_k).
  d->X_WB[0].setIdentity();
  for (int k = 0; k < kDof; ++k) {
    const auto K = static_cast<size_t>(k);
    const auto R_WB = d->X_WB[K].linear();
    Eigen::Matrix3d R;  // joint frame in W
    R.noalias() = R_WB * model.X_BJ_[K].linear();
    d->p_WJ[K].noalias() = R_WB * model.X_BJ_[K].translation();
    d->p_WJ[K] += d->X_WB[K].translation();
    d->z_WJ[K] = R.col(2);
    const double c = std::cos(q[k]), s = std::sin(q[k]);
    Eigen::Isometry3d& X = d->X_WB[K + 1];
    X.linear().col(0) = c * R.col(0) + s * R.col(1);
    X.linear().col(1) = c * R.col(1) - s * R.col(0);
    X.linear().col(2) = R.col(2);
    X.translation() = d->p_WJ[K];
  }
  for (size_t l = 0; l < d->X_WL.size(); ++l) {
    const Eigen::Isometry3d& X_WB = d->X_WB[static_cast<size_t>(model.link_body_[l])];
    Eigen::Isometry3d& X_WL = d->X_WL[l];
    X_WL.linear().noalias() = X_WB.linear() * model.X_BL_[l].linear();
    X_WL.translation().noalias() = X_WB.linear() * model.X_BL_[l].translation();
    X_WL.translation() += X_WB.translation();
  }
  for (int s = 0; s < model.num_spheres(); ++s) {
    const Eigen::Isometry3d& X_WB =
        d->X_WB[static_cast<size_t>(model.sphere_body_[static_cast<size_t>(s)])];
    d->p_WS.col(s).noalias() = X_WB.linear() * model.p_BS_.col(s);
    d->p_WS.col(s) += X_WB.translation();
  }
  d->p_WE = d->X_WB[static_cast<size_t>(model.ee_body_)] * model.p_BE_;
}

void ForwardKinematicsWithJacobians(const RobotModel& model, const JointVector& q,
                                    const JointVector& qdot, KinematicsData* d) {
  ForwardKinematics(model, q, d);
  // Body velocities and accelerations at qddot = 0. Joint k's origin o = p_WJ[k] is fixed in body
  // k and is body k+1's origin.
  d->w_WB[0].setZero();
  d->alpha_WB[0].setZero();
  d->v_WB[0].setZero();
  d->a_WB[0].setZero();
  for (int k = 0; k < kDof; ++k) {
    const auto K = static_cast<size_t>(k);
    const Eigen::Vector3d r = d->p_WJ[K] - d->X_WB[K].translation();
    const Eigen::Vector3d& w = d->w_WB[K];
    const Eigen::Vector3d w_x_r = w.cross(r);
    const Eigen::Vector3d s = d->z_WJ[K] * qdot[k];
    d->v_WB[K + 1] = d->v_WB[K] + w_x_r;
    d->a_WB[K + 1] = d->a_WB[K] + d->alpha_WB[K].cross(r) + w.cross(w_x_r);
    d->alpha_WB[K + 1] = d->alpha_WB[K] + w.cross(s);
    d->w_WB[K + 1] = w + s;
  }
  // Affine maps of a point p: column i of J is z_i x (p - o_i) = Skew(z_i) p + o_i x z_i; on body b
  // with o = o_b, v = v_b + w x (p - o) and Jdot qdot = a_b + alpha x (p - o) + w x (w x (p - o)),
  // where w x (w x r) = (w w' - |w|^2 I) r.
  KinematicsData::Affine& f = d->affine;
  for (int i = 0; i < kDof; ++i) {
    const auto I = static_cast<size_t>(i);
    f.G.middleRows<3>(3 * i) = Skew(d->z_WJ[I]);
    f.g.segment<3>(3 * i) = d->p_WJ[I].cross(d->z_WJ[I]);
  }
  for (size_t b = 0; b <= static_cast<size_t>(kDof); ++b) {
    const Eigen::Vector3d& w = d->w_WB[b];
    const Eigen::Vector3d& o = d->X_WB[b].translation();
    const Eigen::Matrix3d A =
        Skew(d->alpha_WB[b]) + w * w.transpose() - w.squaredNorm() * Eigen::Matrix3d::Identity();
    f.K[b].topRows<3>() = Skew(w);
    f.K[b].bottomRows<3>() = A;
    f.k[b].head<3>() = d->v_WB[b] - w.cross(o);
    f.k[b].tail<3>() = d->a_WB[b] - A * o;
  }
  AllSpheres(model.spheres_on_body_, d, std::make_index_sequence<kDof + 1>());
  EndEffector(model.ee_body_, d, std::make_index_sequence<kDof + 1>());
}

void LinkJacobian(const RobotModel& model, const KinematicsData& data, int link, FrameJacobian* J) {
  assert(link >= 0 && link < model.num_links());
  const int b = model.num_supporting_joints(link);
  const Eigen::Vector3d p = data.X_WL[static_cast<size_t>(link)].translation();
  for (int i = 0; i < b; ++i) {
    J->col(i) << data.z_WJ[static_cast<size_t>(i)].cross(p - data.p_WJ[static_cast<size_t>(i)]),
        data.z_WJ[static_cast<size_t>(i)];
  }
  for (int i = b; i < kDof; ++i) J->col(i).setZero();
}

}  // namespace foresight::manipulation
