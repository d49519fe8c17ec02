// The robot model against independent computations: KDL chains built from the same URDF by hand
// (as kdl_parser does; not packaged in Debian), central finite differences, the README's numbers,
// and bad input. The kinematics tests run on the Panda (../shared/data) and on a synthetic robot
// with tilted axes, rotated joint origins and fixed joints in and off the chain.

#include "inference/manipulation/robot_model.h"

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/jntarrayvel.hpp>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "inference/manipulation/urdf_util.h"
#define FORESIGHT_ALLOC_COUNTER_MALLOC  // count Eigen's malloc too
#include "tests/alloc_counter.h"        // replaces operator new: one per binary
#include "tests/test_util.h"

namespace foresight::manipulation {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::ReadText;
using foresight::testing::TempDir;
using foresight::testing::WriteText;

/// ../shared/data/franka_panda, or "" when the shared data is absent.
std::string FrankaDir() {
  const std::string data = foresight::testing::SharedDataDir();
  return data.empty() ? "" : data + "/franka_panda";
}

#define SKIP_WITHOUT_PANDA()                                                              \
  const std::string franka = FrankaDir();                                                 \
  if (franka.empty())                                                                     \
  GTEST_SKIP() << "../shared/data (franka_panda) is absent: set FORESIGHT_SOURCE_DIR to " \
                  "the repository root next to shared/"

// ---- independent reference: KDL chains from urdfdom ------------------------------------------

KDL::Frame ToKdl(const urdf::Pose& pose) {
  return KDL::Frame(
      KDL::Rotation::Quaternion(pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w),
      KDL::Vector(pose.position.x, pose.position.y, pose.position.z));
}

Eigen::Matrix4d ToEigen(const KDL::Frame& f) {
  Eigen::Matrix4d X = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X(r, c) = f.M(r, c);
    X(r, 3) = f.p(r);
  }
  return X;
}

/// A KDL chain from the URDF root to a link (and optionally on to a point fixed in that link),
/// with its solvers. Segments as kdl_parser makes them: joint rotating about the axis expressed
/// in the parent frame through the joint origin, then the joint's origin transform as the tip.
struct KdlChain {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  std::unique_ptr<KDL::ChainJntToJacDotSolver> jac_dot;

  KdlChain(const urdf::ModelInterface& urdf, const std::string& tip, const Eigen::Vector3d* p_tip) {
    std::vector<urdf::JointConstSharedPtr> joints;
    for (auto link = urdf.getLink(tip); link->parent_joint;
         link = urdf.getLink(link->parent_joint->parent_link_name))
      joints.push_back(link->parent_joint);
    std::reverse(joints.begin(), joints.end());
    for (const auto& j : joints) {
      const KDL::Frame F = ToKdl(j->parent_to_joint_origin_transform);
      const KDL::Joint joint =
          j->type == urdf::Joint::FIXED
              ? KDL::Joint(j->name, KDL::Joint::Fixed)
              : KDL::Joint(j->name, F.p, F.M * KDL::Vector(j->axis.x, j->axis.y, j->axis.z),
                           KDL::Joint::RotAxis);
      chain.addSegment(KDL::Segment(j->child_link_name, joint, F));
    }
    if (p_tip != nullptr)
      chain.addSegment(
          KDL::Segment("point", KDL::Joint(KDL::Joint::Fixed),
                       KDL::Frame(KDL::Vector((*p_tip)[0], (*p_tip)[1], (*p_tip)[2]))));
    fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(chain);
    jac = std::make_unique<KDL::ChainJntToJacSolver>(chain);
    jac_dot = std::make_unique<KDL::ChainJntToJacDotSolver>(chain);
  }
  int joints() const { return static_cast<int>(chain.getNrOfJoints()); }
  KDL::JntArray Head(const JointVector& q) const {
    KDL::JntArray out(chain.getNrOfJoints());
    for (int i = 0; i < joints(); ++i) out(i) = q[i];
    return out;
  }
  Eigen::Matrix4d Pose(const JointVector& q) const {
    KDL::Frame f;
    EXPECT_GE(fk->JntToCart(Head(q), f), 0);
    return ToEigen(f);
  }
  /// [6 x kDof] (linear; angular) Jacobian referenced at the tip, in the base frame.
  FrameJacobian Jacobian(const JointVector& q) const {
    KDL::Jacobian J(chain.getNrOfJoints());
    EXPECT_GE(jac->JntToJac(Head(q), J), 0);
    FrameJacobian out = FrameJacobian::Zero();
    for (int i = 0; i < joints(); ++i) out.col(i) = J.data.col(i);
    return out;
  }
  /// (dJ/dt) qdot of the tip (linear; angular), hybrid representation.
  Eigen::Matrix<double, 6, 1> JdotQdot(const JointVector& q, const JointVector& qdot) const {
    KDL::JntArrayVel qv(Head(q), Head(qdot));
    KDL::Twist t;
    EXPECT_GE(jac_dot->JntToJacDot(qv, t), 0);
    Eigen::Matrix<double, 6, 1> out;
    out << t.vel(0), t.vel(1), t.vel(2), t.rot(0), t.rot(1), t.rot(2);
    return out;
  }
};

// ---- robots under test ---------------------------------------------------------------------

struct RobotFiles {
  std::string urdf, spheres, srdf;
};

/// A 7-joint robot with random unit axes (not along z), rotated joint origins, a fixed link inside
/// the chain (joint 4 hangs off it), a fixed branch off link 2 and a fixed tool: exercises every
/// code path the Panda does not (its axes are all z).
RobotFiles WriteSyntheticRobot(const TempDir& dir) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::ostringstream urdf;
  urdf.precision(17);
  const auto origin = [&] {
    std::ostringstream o;
    o.precision(17);
    o << "<origin xyz=\"" << 0.15 * u(rng) << " " << 0.15 * u(rng) << " " << 0.15 * u(rng)
      << "\" rpy=\"" << 3 * u(rng) << " " << 1.5 * u(rng) << " " << 3 * u(rng) << "\"/>";
    return o.str();
  };
  const auto axis = [&] {
    Eigen::Vector3d a(u(rng), u(rng), u(rng));
    a.normalize();
    std::ostringstream o;
    o.precision(17);
    o << "<axis xyz=\"" << a[0] << " " << a[1] << " " << a[2] << "\"/>";
    return o.str();
  };
  urdf << "<robot name=\"synthetic\">\n";
  for (const char* link : {"base", "l1", "l2", "l3", "mid", "l4", "l5", "l6", "l7", "side", "tool"})
    urdf << "  <link name=\"" << link << "\"/>\n";
  const std::vector<std::pair<std::string, std::string>> chain = {
      {"base", "l1"}, {"l1", "l2"}, {"l2", "l3"}, {"mid", "l4"},
      {"l4", "l5"},   {"l5", "l6"}, {"l6", "l7"}};
  for (size_t k = 0; k < chain.size(); ++k)
    urdf << "  <joint name=\"j" << k + 1 << "\" type=\"revolute\">" << origin() << axis()
         << "<parent link=\"" << chain[k].first << "\"/><child link=\"" << chain[k].second
         << "\"/><limit lower=\"-2\" upper=\"2.5\" velocity=\"1.5\" effort=\"1\"/></joint>\n";
  for (const auto& [parent, child] : std::vector<std::pair<std::string, std::string>>{
           {"l3", "mid"}, {"l2", "side"}, {"l7", "tool"}})
    urdf << "  <joint name=\"fix_" << child << "\" type=\"fixed\">" << origin() << "<parent link=\""
         << parent << "\"/><child link=\"" << child << "\"/></joint>\n";
  urdf << "</robot>\n";
  RobotFiles files{dir.File("synthetic.urdf"), dir.File("synthetic.csv"), ""};
  WriteText(files.urdf, urdf.str());
  std::ostringstream csv;
  csv << "link,x,y,z,radius\n";
  for (const char* link : {"base", "l1", "side", "l2", "mid", "l3", "l4", "l5", "l6", "l7", "tool"})
    for (int s = 0; s < 2; ++s)
      csv << link << "," << 0.1 * u(rng) << "," << 0.1 * u(rng) << "," << 0.1 * u(rng) << ",0.03\n";
  WriteText(files.spheres, csv.str());
  return files;
}

JointVector RandomConfiguration(const JointLimits& limits, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(0, 1);
  JointVector q;
  for (int i = 0; i < kDof; ++i)
    q[i] = limits.lower[i] + u(*rng) * (limits.upper[i] - limits.lower[i]);
  return q;
}

JointVector RandomVelocity(const JointLimits& limits, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  JointVector qdot;
  for (int i = 0; i < kDof; ++i) qdot[i] = u(*rng) * limits.velocity[i];
  return qdot;
}

/// Largest errors of one robot against KDL and finite differences (printed for the record).
struct Errors {
  double frame = 0, sphere = 0, ee = 0, jacobian = 0, link_jacobian = 0, jdot_kdl = 0;
  double jacobian_fd = 0, velocity_fd = 0, jdot_fd = 0;
};

/// Compares our kinematics with KDL (frames, sphere centres, EE, all Jacobians, Jdot qdot) and
/// with central differences (J, J qdot, Jdot qdot) on `configurations` random states.
Errors CheckKinematics(const RobotFiles& files, int configurations) {
  const RobotModel model = RobotModel::Load(files.urdf, files.spheres, files.srdf);
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDFFile(files.urdf);
  std::vector<std::unique_ptr<KdlChain>> links, spheres;
  for (int l = 0; l < model.num_links(); ++l) {
    links.push_back(std::make_unique<KdlChain>(*urdf, model.link_name(l), nullptr));
    EXPECT_EQ(links.back()->joints(), model.num_supporting_joints(l)) << model.link_name(l);
  }
  for (const CollisionSphere& s : model.spheres())
    spheres.push_back(std::make_unique<KdlChain>(*urdf, s.link_name, &s.p_LS));
  const KdlChain& ee = *links[static_cast<size_t>(model.end_effector_link())];

  KinematicsData data = model.MakeData(), plus = model.MakeData(), minus = model.MakeData();
  std::mt19937_64 rng(5);
  Errors e;
  const auto track = [](double* worst, double error) { *worst = std::max(*worst, error); };
  constexpr double h = 1e-6;
  for (int c = 0; c < configurations; ++c) {
    const JointVector q = RandomConfiguration(model.limits(), &rng);
    const JointVector qdot = RandomVelocity(model.limits(), &rng);
    ForwardKinematicsWithJacobians(model, q, qdot, &data);
    for (int l = 0; l < model.num_links(); ++l) {
      const KdlChain& ref = *links[static_cast<size_t>(l)];
      track(&e.frame,
            (data.X_WL[static_cast<size_t>(l)].matrix() - ref.Pose(q)).cwiseAbs().maxCoeff());
      FrameJacobian J;
      LinkJacobian(model, data, l, &J);
      track(&e.link_jacobian, (J - ref.Jacobian(q)).cwiseAbs().maxCoeff());
    }
    for (int s = 0; s < model.num_spheres(); ++s) {
      const KdlChain& ref = *spheres[static_cast<size_t>(s)];
      const auto S = static_cast<size_t>(s);
      track(&e.sphere,
            (data.p_WS.col(s) - ref.Pose(q).topRightCorner<3, 1>()).cwiseAbs().maxCoeff());
      track(&e.jacobian, (data.J_WS[S] - ref.Jacobian(q).topRows<3>()).cwiseAbs().maxCoeff());
      track(&e.jdot_kdl,
            (data.Jdot_qdot_WS[S] - ref.JdotQdot(q, qdot).head<3>()).cwiseAbs().maxCoeff());
      // Columns of joints that do not move the sphere are exactly zero.
      const int b = ref.joints();
      EXPECT_TRUE((data.J_WS[S].rightCols(kDof - b).array() == 0).all()) << "sphere " << s;
    }
    track(&e.ee, (data.p_WE - ee.Pose(q).topRightCorner<3, 1>()).cwiseAbs().maxCoeff());
    track(&e.jacobian, (data.J_WE - ee.Jacobian(q).topRows<3>()).cwiseAbs().maxCoeff());
    track(&e.jdot_kdl, (data.Jdot_qdot_WE - ee.JdotQdot(q, qdot).head<3>()).cwiseAbs().maxCoeff());

    // Central differences: column i of J, J qdot (velocity) and Jdot qdot along qdot.
    for (int i = 0; i < kDof; ++i) {
      ForwardKinematics(model, q + h * JointVector::Unit(i), &plus);
      ForwardKinematics(model, q - h * JointVector::Unit(i), &minus);
      for (int s = 0; s < model.num_spheres(); ++s) {
        const Eigen::Vector3d fd = (plus.p_WS.col(s) - minus.p_WS.col(s)) / (2 * h);
        track(&e.jacobian_fd,
              (data.J_WS[static_cast<size_t>(s)].col(i) - fd).cwiseAbs().maxCoeff());
      }
      track(&e.jacobian_fd,
            (data.J_WE.col(i) - (plus.p_WE - minus.p_WE) / (2 * h)).cwiseAbs().maxCoeff());
    }
    ForwardKinematicsWithJacobians(model, q + h * qdot, qdot, &plus);
    ForwardKinematicsWithJacobians(model, q - h * qdot, qdot, &minus);
    for (int s = 0; s < model.num_spheres(); ++s) {
      const auto S = static_cast<size_t>(s);
      const Eigen::Vector3d v_fd = (plus.p_WS.col(s) - minus.p_WS.col(s)) / (2 * h);
      track(&e.velocity_fd, (data.v_WS.col(s) - v_fd).cwiseAbs().maxCoeff());
      EXPECT_LT((data.v_WS.col(s) - data.J_WS[S] * qdot).cwiseAbs().maxCoeff(), 1e-12);
      const Eigen::Vector3d jdot_fd = (plus.J_WS[S] - minus.J_WS[S]) * qdot / (2 * h);
      track(&e.jdot_fd, (data.Jdot_qdot_WS[S] - jdot_fd).cwiseAbs().maxCoeff());
    }
    track(&e.velocity_fd, (data.v_WE - (plus.p_WE - minus.p_WE) / (2 * h)).cwiseAbs().maxCoeff());
    track(&e.jdot_fd,
          (data.Jdot_qdot_WE - (plus.J_WE - minus.J_WE) * qdot / (2 * h)).cwiseAbs().maxCoeff());
  }
  std::printf(
      "[ errors   ] %s vs KDL: frames %.1e, spheres %.1e, EE %.1e, J %.1e, link J %.1e, Jdot qdot "
      "%.1e; vs central differences: J %.1e, J qdot %.1e, Jdot qdot %.1e\n",
      model.name().c_str(), e.frame, e.sphere, e.ee, e.jacobian, e.link_jacobian, e.jdot_kdl,
      e.jacobian_fd, e.velocity_fd, e.jdot_fd);
  return e;
}

void ExpectMatchesReferences(const Errors& e) {
  EXPECT_LT(e.frame, 1e-10);
  EXPECT_LT(e.sphere, 1e-10);
  EXPECT_LT(e.ee, 1e-10);
  EXPECT_LT(e.jacobian, 1e-10);
  EXPECT_LT(e.link_jacobian, 1e-10);
  EXPECT_LT(e.jdot_kdl, 1e-10);
  EXPECT_LT(e.jacobian_fd, 1e-7);
  EXPECT_LT(e.velocity_fd, 1e-7);
  EXPECT_LT(e.jdot_fd, 1e-6);
}

// ---- the Panda: facts from the files and the README ------------------------------------------

TEST(PandaModel, JointsLinksAndLimitsMatchTheReadme) {
  SKIP_WITHOUT_PANDA();
  const RobotModel model = RobotModel::LoadPanda(franka);
  EXPECT_EQ(model.name(), "panda");
  for (int k = 0; k < kDof; ++k)
    EXPECT_EQ(model.joint_names()[static_cast<size_t>(k)], "panda_joint" + std::to_string(k + 1));
  const JointLimits& l = model.limits();
  JointVector hard_upper, soft_lower, soft_upper;
  hard_upper << 2.9671, 1.8326, 2.9671, 0.0873, 2.9671, 3.8223, 2.9671;
  JointVector hard_lower;
  hard_lower << -2.9671, -1.8326, -2.9671, -3.1416, -2.9671, -0.0873, -2.9671;
  soft_lower << -2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973;
  soft_upper << 2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973;
  JointVector velocity;
  velocity << 2.3925, 2.3925, 2.3925, 2.3925, 2.8710, 2.8710, 2.8710;
  EXPECT_EQ(l.lower, hard_lower);
  EXPECT_EQ(l.upper, hard_upper);
  EXPECT_EQ(l.soft_lower, soft_lower);
  EXPECT_EQ(l.soft_upper, soft_upper);
  EXPECT_EQ(l.velocity, velocity);

  EXPECT_EQ(model.num_links(), 13);
  EXPECT_EQ(model.link_name(0), "panda_link0");
  EXPECT_EQ(model.link_parent(0), -1);
  EXPECT_EQ(model.link_name(model.end_effector_link()), "panda_grasptarget");
  EXPECT_EQ(model.link_parent(model.LinkIndex("panda_hand")), model.LinkIndex("panda_link8"));
  for (int l2 = 1; l2 < model.num_links(); ++l2) EXPECT_LT(model.link_parent(l2), l2);
  // Fixed joints fold into the body of the last arm joint; fingers are fixed in this URDF.
  for (const char* name : {"panda_link7", "panda_link8", "panda_hand", "panda_leftfinger",
                           "panda_rightfinger", "panda_grasptarget"})
    EXPECT_EQ(model.num_supporting_joints(model.LinkIndex(name)), 7) << name;
  EXPECT_EQ(model.num_supporting_joints(model.LinkIndex("panda_link3")), 3);
  EXPECT_EQ(model.num_supporting_joints(0), 0);
  ExpectErrorContains([&] { model.LinkIndex("panda_link9"); }, {"panda_link9", "panda_hand"});
}

TEST(PandaModel, SpheresMatchTheCsv) {
  SKIP_WITHOUT_PANDA();
  const RobotModel model = RobotModel::LoadPanda(franka);
  ASSERT_EQ(model.num_spheres(), 59);
  const CollisionSphere& first = model.spheres().front();
  EXPECT_EQ(first.link_name, "panda_link0");
  EXPECT_EQ(first.link, 0);
  EXPECT_EQ(first.p_LS, Eigen::Vector3d(0, 0, 0.05));
  EXPECT_EQ(first.radius, 0.08);
  const CollisionSphere& last = model.spheres().back();
  EXPECT_EQ(last.link_name, "panda_rightfinger");
  EXPECT_EQ(last.p_LS, Eigen::Vector3d(0, -0.008, 0.044));
  EXPECT_EQ(last.radius, 0.012);
  std::map<std::string, int> per_link;
  for (const CollisionSphere& s : model.spheres()) {
    ++per_link[s.link_name];
    EXPECT_EQ(model.link_name(s.link), s.link_name);
  }
  EXPECT_EQ(per_link["panda_hand"], 18);
  EXPECT_EQ(per_link["panda_link5"], 12);
  EXPECT_EQ(per_link.count("panda_link8"), 0u);
}

TEST(PandaModel, SelfCollisionPairsFollowTheSrdf) {
  SKIP_WITHOUT_PANDA();
  const RobotModel model = RobotModel::LoadPanda(franka);
  const RobotModel no_srdf =
      RobotModel::Load(franka + "/panda.urdf", franka + "/spheres_vamp.csv", "");
  const auto links_of = [](const RobotModel& m) {
    std::set<std::pair<std::string, std::string>> out;
    for (const auto& [i, j] : m.self_collision_pairs()) {
      EXPECT_LT(i, j);
      const CollisionSphere& a = m.spheres()[static_cast<size_t>(i)];
      const CollisionSphere& b = m.spheres()[static_cast<size_t>(j)];
      EXPECT_GT(std::abs(m.num_supporting_joints(a.link) - m.num_supporting_joints(b.link)), 1)
          << a.link_name << " " << b.link_name << ": rigid or adjacent";
      out.emplace(std::min(a.link_name, b.link_name), std::max(a.link_name, b.link_name));
    }
    return out;
  };
  const auto pairs = links_of(model);
  const auto all = links_of(no_srdf);
  EXPECT_TRUE(
      std::is_sorted(model.self_collision_pairs().begin(), model.self_collision_pairs().end()));
  EXPECT_EQ(model.self_collision_pairs().size(), 690u);
  // link0-link2 is not adjacent: only the SRDF ("Never") removes it; same for link2-link6.
  EXPECT_TRUE(model.CollisionDisabled(model.LinkIndex("panda_link2"), 0));
  EXPECT_TRUE(model.CollisionDisabled(0, model.LinkIndex("panda_link2")));
  EXPECT_FALSE(model.CollisionDisabled(0, model.LinkIndex("panda_hand")));
  EXPECT_EQ(pairs.count({"panda_link0", "panda_link2"}), 0u);
  EXPECT_EQ(pairs.count({"panda_link2", "panda_link6"}), 0u);
  EXPECT_EQ(all.count({"panda_link0", "panda_link2"}), 1u);
  EXPECT_EQ(all.count({"panda_link2", "panda_link6"}), 1u);
  EXPECT_EQ(pairs.count({"panda_hand", "panda_link0"}), 1u);
  EXPECT_EQ(pairs.count({"panda_link5", "panda_link7"}), 1u);
  // Rigidly attached and adjacent links never pair, with or without the SRDF.
  EXPECT_EQ(all.count({"panda_hand", "panda_link7"}), 0u);
  EXPECT_EQ(all.count({"panda_link1", "panda_link2"}), 0u);
  EXPECT_GT(no_srdf.self_collision_pairs().size(), model.self_collision_pairs().size());
}

TEST(PandaModel, KnownPoses) {
  SKIP_WITHOUT_PANDA();
  const RobotModel model = RobotModel::LoadPanda(franka);
  KinematicsData data = model.MakeData();
  ForwardKinematics(model, JointVector::Zero(), &data);
  const Eigen::Vector3d link8 =
      data.X_WL[static_cast<size_t>(model.LinkIndex("panda_link8"))].translation();
  EXPECT_LT((link8 - Eigen::Vector3d(0.088, 0, 0.926)).cwiseAbs().maxCoeff(), 1e-12)
      << link8.transpose();
  JointVector ready;
  ready << 0, -0.785, 0, -2.356, 0, 1.571, 0.785;
  ForwardKinematics(model, ready, &data);
  EXPECT_LT((data.p_WE - Eigen::Vector3d(0.307, 0, 0.485)).cwiseAbs().maxCoeff(), 1e-3)
      << data.p_WE.transpose();
  EXPECT_EQ(data.p_WE, data.X_WL[static_cast<size_t>(model.end_effector_link())].translation());
  // The grasp target sits 0.105 m along the hand's z axis, which points down in the ready pose.
  const Eigen::Isometry3d& hand = data.X_WL[static_cast<size_t>(model.LinkIndex("panda_hand"))];
  EXPECT_LT((hand.linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-3);
}

// ---- kinematics against KDL and finite differences (Panda and synthetic) ----------------------

TEST(Kinematics, PandaMatchesKdlAndFiniteDifferences) {
  SKIP_WITHOUT_PANDA();
  ExpectMatchesReferences(CheckKinematics(
      {franka + "/panda.urdf", franka + "/spheres_vamp.csv", franka + "/panda.srdf"}, 100));
}

TEST(Kinematics, SyntheticRobotMatchesKdlAndFiniteDifferences) {
  const TempDir dir;
  ExpectMatchesReferences(CheckKinematics(WriteSyntheticRobot(dir), 100));
}

TEST(Kinematics, PositionsAloneMatchTheJacobianPass) {
  const TempDir dir;
  const RobotFiles files = WriteSyntheticRobot(dir);
  const RobotModel model = RobotModel::Load(files.urdf, files.spheres, "");
  KinematicsData a = model.MakeData(), b = model.MakeData();
  std::mt19937_64 rng(2);
  for (int c = 0; c < 10; ++c) {
    const JointVector q = RandomConfiguration(model.limits(), &rng);
    ForwardKinematics(model, q, &a);
    ForwardKinematicsWithJacobians(model, q, RandomVelocity(model.limits(), &rng), &b);
    EXPECT_EQ(a.p_WS, b.p_WS);
    EXPECT_EQ(a.p_WE, b.p_WE);
    for (int l = 0; l < model.num_links(); ++l)
      EXPECT_EQ(a.X_WL[static_cast<size_t>(l)].matrix(), b.X_WL[static_cast<size_t>(l)].matrix());
  }
}

TEST(SyntheticModel, DefaultsAndPairRule) {
  const TempDir dir;
  const RobotFiles files = WriteSyntheticRobot(dir);
  const RobotModel model = RobotModel::Load(files.urdf, files.spheres, "");
  // Without panda_grasptarget the end effector is the child link of the last arm joint.
  EXPECT_EQ(model.link_name(model.end_effector_link()), "l7");
  // Without <safety_controller> the soft limits are the hard ones.
  EXPECT_EQ(model.limits().soft_lower, model.limits().lower);
  EXPECT_EQ(model.limits().soft_upper, model.limits().upper);
  EXPECT_EQ(model.limits().velocity, JointVector::Constant(1.5));
  // "mid" hangs off l3 by a fixed joint and carries joint 4: it moves with body 3.
  EXPECT_EQ(model.num_supporting_joints(model.LinkIndex("mid")), 3);
  EXPECT_EQ(model.num_supporting_joints(model.LinkIndex("side")), 2);
  EXPECT_EQ(model.num_supporting_joints(model.LinkIndex("tool")), 7);
  // Without an SRDF only rigid (same body) and adjacent (bodies one joint apart) pairs are out.
  int expected = 0;
  for (int i = 0; i < model.num_spheres(); ++i)
    for (int j = i + 1; j < model.num_spheres(); ++j)
      expected +=
          std::abs(model.num_supporting_joints(model.spheres()[static_cast<size_t>(i)].link) -
                   model.num_supporting_joints(model.spheres()[static_cast<size_t>(j)].link)) > 1;
  EXPECT_EQ(static_cast<int>(model.self_collision_pairs().size()), expected);
}

/// Heap allocations (operator new, and malloc/calloc/realloc where interposed) during `fn`.
long AllocationsDuring(const std::function<void()>& fn) {
  g_allocations = 0;
  g_counting = true;
  fn();
  g_counting = false;
  return g_allocations.load();
}

void ExpectKinematicsAllocateNothing(const RobotModel& model) {
  KinematicsData data = model.MakeData();
  std::mt19937_64 rng(4);
  const JointVector q = RandomConfiguration(model.limits(), &rng);
  const JointVector qdot = RandomVelocity(model.limits(), &rng);
  FrameJacobian J;
  ForwardKinematicsWithJacobians(model, q, qdot, &data);  // warm-up
  EXPECT_EQ(AllocationsDuring([&] {
              for (int i = 0; i < 10; ++i) {
                ForwardKinematics(model, q, &data);
                ForwardKinematicsWithJacobians(model, q, qdot, &data);
                LinkJacobian(model, data, model.end_effector_link(), &J);
              }
            }),
            0)
      << model.name() << ": heap allocations on the kinematics path";
  EXPECT_TRUE(data.p_WS.allFinite() && J.allFinite());
}

TEST(Kinematics, AllocatesNothing) {
  const TempDir dir;
  const RobotFiles files = WriteSyntheticRobot(dir);
  const RobotModel synthetic = RobotModel::Load(files.urdf, files.spheres, "");
#ifndef FORESIGHT_COUNTS_MALLOC
  GTEST_SKIP() << "malloc is not counted in this build (neither glibc nor AddressSanitizer)";
#endif
  // The counter sees Eigen's heap (malloc), not only operator new.
  volatile double sink = 0;
  EXPECT_GT(AllocationsDuring([&] { sink = Eigen::VectorXd::Ones(40).eval().sum(); }), 0);
  EXPECT_GT(AllocationsDuring([&] { synthetic.MakeData(); }), 0);
  ExpectKinematicsAllocateNothing(synthetic);
  const std::string franka = FrankaDir();
  if (!franka.empty()) ExpectKinematicsAllocateNothing(RobotModel::LoadPanda(franka));
}

// ---- bad input --------------------------------------------------------------------------------

/// Writes (edited) copies of the Panda files to a temp dir and loads them.
class PandaBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    franka_ = FrankaDir();
    if (franka_.empty()) GTEST_SKIP() << "../shared/data (franka_panda) is absent";
    urdf_ = ReadText(franka_ + "/panda.urdf");
    csv_ = ReadText(franka_ + "/spheres_vamp.csv");
    srdf_ = ReadText(franka_ + "/panda.srdf");
  }
  /// `text` with the first occurrence of `from` replaced by `to` (which must exist).
  static std::string Edit(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << "'" << from << "' not in the file";
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
  }
  /// Expects loading the three texts to fail with a message containing `parts`.
  void ExpectLoadError(const std::string& urdf, const std::string& csv, const std::string& srdf,
                       std::vector<std::string> parts) {
    WriteText(dir_.File("panda.urdf"), urdf);
    WriteText(dir_.File("spheres_vamp.csv"), csv);
    WriteText(dir_.File("panda.srdf"), srdf);
    ExpectErrorContains(
        [&] {
          RobotModel::Load(dir_.File("panda.urdf"), dir_.File("spheres_vamp.csv"),
                           dir_.File("panda.srdf"));
        },
        parts);
  }
  std::string Urdf() const { return dir_.File("panda.urdf"); }
  std::string Csv() const { return dir_.File("spheres_vamp.csv"); }
  std::string Srdf() const { return dir_.File("panda.srdf"); }

  TempDir dir_;
  std::string franka_, urdf_, csv_, srdf_;
};

TEST_F(PandaBadInput, MissingFiles) {
  ExpectErrorContains([&] { RobotModel::Load(Urdf(), franka_ + "/spheres_vamp.csv", ""); },
                      {"cannot read URDF file", Urdf()});
  ExpectErrorContains([&] { RobotModel::Load(franka_ + "/panda.urdf", Csv(), ""); },
                      {"cannot read spheres file", Csv()});
  ExpectErrorContains(
      [&] { RobotModel::Load(franka_ + "/panda.urdf", franka_ + "/spheres_vamp.csv", Srdf()); },
      {"cannot read SRDF file", Srdf()});
  ExpectErrorContains([&] { RobotModel::LoadPanda(dir_.path()); }, {"panda.urdf", dir_.path()});
}

// Issue 18 (found by fuzzing): TinyXML reads past the text on a truncated UTF-8 sequence, so XML
// that is not UTF-8 is refused before parsing, naming the byte.
TEST(UrdfText, NotUtf8IsAnErrorNamingTheByte) {
  EXPECT_NO_THROW(urdf_util::CheckUtf8(
      "<robot name=\"caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80\"/>", "a.urdf"));
  ExpectErrorContains([] { urdf_util::CheckUtf8("<robot/>\xF0\x9F", "a.urdf"); },
                      {"a.urdf", "byte 8", "UTF-8"});
  ExpectErrorContains([] { urdf_util::CheckUtf8("<r \x89/>", "b.srdf"); }, {"b.srdf", "byte 3"});
  ExpectErrorContains([] { urdf_util::CheckUtf8("<r \xC3(/>", "c.urdf"); }, {"c.urdf", "byte 3"});
}

TEST_F(PandaBadInput, UrdfErrors) {
  ExpectLoadError("<robot name=\"x\"><link name=\"a\"></robot>", csv_, srdf_,
                  {Urdf(), "not a valid URDF"});
  ExpectLoadError(urdf_ + "\xE2\x82", csv_, srdf_, {Urdf(), "UTF-8"});
  ExpectLoadError(urdf_, csv_, srdf_ + "\xC3", {Srdf(), "UTF-8"});
  // A revolute arm joint without <limit> (urdfdom's reason is passed on).
  ExpectLoadError(
      Edit(urdf_, "<limit effort=\"87\" lower=\"-3.1416\" upper=\"0.0873\" velocity=\"2.3925\" />",
           ""),
      csv_, srdf_, {Urdf(), "panda_joint4", "limits"});
  ExpectLoadError(Edit(urdf_, "lower=\"-3.1416\" upper=\"0.0873\"", "lower=\"0.5\" upper=\"0.5\""),
                  csv_, srdf_, {Urdf(), "panda_joint4", "lower < upper", "0.5"});
  ExpectLoadError(Edit(urdf_, "lower=\"-1.8326\" upper=\"1.8326\" velocity=\"2.3925\"",
                       "lower=\"-1.8326\" upper=\"1.8326\" velocity=\"0\""),
                  csv_, srdf_, {Urdf(), "panda_joint2", "velocity > 0"});
  // A missing joint leaves its child link without a parent: two roots.
  const auto j4 = urdf_.find("<joint name=\"panda_joint4\"");
  const auto j4_end = urdf_.find("</joint>", j4) + std::string("</joint>").size();
  ExpectLoadError(urdf_.substr(0, j4) + urdf_.substr(j4_end), csv_, srdf_,
                  {Urdf(), "not a valid URDF", "root"});
  // An arm joint made fixed: six arm joints.
  ExpectLoadError(Edit(urdf_, "<joint name=\"panda_joint4\" type=\"revolute\">",
                       "<joint name=\"panda_joint4\" type=\"fixed\">"),
                  csv_, srdf_, {Urdf(), "expected 7 revolute arm joints, found 6", "panda_joint5"});
  ExpectLoadError(Edit(urdf_, "<joint name=\"panda_joint3\" type=\"revolute\">",
                       "<joint name=\"panda_joint3\" type=\"continuous\">"),
                  csv_, srdf_, {Urdf(), "panda_joint3", "continuous"});
  // Prismatic fingers (as in franka_ros) are not supported: the model holds them fixed.
  ExpectLoadError(
      Edit(urdf_, "<joint name=\"panda_finger_joint1\" type=\"fixed\">",
           "<joint name=\"panda_finger_joint1\" type=\"prismatic\"><limit effort=\"20\" "
           "lower=\"0\" upper=\"0.04\" velocity=\"0.2\"/>"),
      csv_, srdf_, {Urdf(), "panda_finger_joint1", "prismatic"});
  // A revolute finger adds an eighth arm joint; two make a branch.
  const std::string one_finger =
      Edit(urdf_, "<joint name=\"panda_finger_joint1\" type=\"fixed\">",
           "<joint name=\"panda_finger_joint1\" type=\"revolute\"><limit "
           "effort=\"1\" lower=\"0\" upper=\"0.04\" velocity=\"0.2\"/>");
  ExpectLoadError(one_finger, csv_, srdf_, {Urdf(), "found 8", "panda_finger_joint1"});
  const std::string two_fingers =
      Edit(one_finger, "<joint name=\"panda_finger_joint2\" type=\"fixed\">",
           "<joint name=\"panda_finger_joint2\" type=\"revolute\"><limit effort=\"1\" "
           "lower=\"0\" upper=\"0.04\" velocity=\"0.2\"/>");
  // panda_finger_joint2 mimics panda_finger_joint1 (ignored while both are fixed).
  ExpectLoadError(two_fingers, csv_, srdf_, {Urdf(), "panda_finger_joint2", "mimic"});
  ExpectLoadError(Edit(two_fingers, "<mimic joint=\"panda_finger_joint1\"></mimic>", ""), csv_,
                  srdf_, {Urdf(), "panda_finger_joint2", "one serial chain"});
  ExpectLoadError(Edit(urdf_,
                       "<safety_controller k_position=\"100.0\" k_velocity=\"40.0\" "
                       "soft_lower_limit=\"-1.7628\" soft_upper_limit=\"1.7628\"/>",
                       "<safety_controller k_position=\"100.0\" k_velocity=\"40.0\" "
                       "soft_lower_limit=\"1\" soft_upper_limit=\"-1\"/>"),
                  csv_, srdf_, {Urdf(), "panda_joint2", "soft_lower_limit < soft_upper_limit"});
}

TEST_F(PandaBadInput, TextsNameTheirSource) {
  const RobotModel model = RobotModel::FromText(urdf_, csv_, srdf_, "<test Panda>");
  EXPECT_EQ(model.num_spheres(), 59);
  EXPECT_EQ(model.self_collision_pairs().size(), 690u);
  EXPECT_EQ(RobotModel::FromText(urdf_, csv_, "", "<test Panda>").self_collision_pairs().size(),
            RobotModel::Load(franka_ + "/panda.urdf", franka_ + "/spheres_vamp.csv", "")
                .self_collision_pairs()
                .size());
  ExpectErrorContains(
      [&] {
        RobotModel::FromText(urdf_, Edit(csv_, "panda_link1,", "nowhere,"), srdf_, "<test Panda>");
      },
      {"<test Panda> spheres:3", "unknown link 'nowhere'"});
  ExpectErrorContains([&] { RobotModel::FromText("<robot/>", csv_, srdf_, "<test Panda>"); },
                      {"<test Panda> URDF", "not a valid URDF"});
  ExpectErrorContains([&] { RobotModel::FromText(urdf_, csv_, "<robot", "<test Panda>"); },
                      {"<test Panda> SRDF:1", "not valid XML"});
}

TEST_F(PandaBadInput, PandaJointNames) {
  WriteText(dir_.File("panda.urdf"), Edit(urdf_, "name=\"panda_joint3\"", "name=\"elbow\""));
  WriteText(dir_.File("spheres_vamp.csv"), csv_);
  WriteText(dir_.File("panda.srdf"), srdf_);
  ExpectErrorContains([&] { RobotModel::LoadPanda(dir_.path()); },
                      {"panda.urdf", "arm joint 3 is 'elbow'", "panda_joint3"});
}

TEST_F(PandaBadInput, SphereErrors) {
  ExpectLoadError(urdf_, Edit(csv_, "panda_link1,0.0,-0.08", "panda_link99,0.0,-0.08"), srdf_,
                  {Csv() + ":3", "unknown link 'panda_link99'"});
  ExpectLoadError(urdf_, Edit(csv_, "panda_link1,0.0,-0.08,0.0,0.06", "panda_link1,0.0,-0.08,0.06"),
                  srdf_, {Csv() + ":3", "expected 5", "got 4"});
  ExpectLoadError(urdf_,
                  Edit(csv_, "panda_link1,0.0,-0.08,0.0,0.06", "panda_link1,0.0,abc,0.0,0.06"),
                  srdf_, {Csv() + ":3", "y 'abc'"});
  ExpectLoadError(urdf_,
                  Edit(csv_, "panda_link1,0.0,-0.08,0.0,0.06", "panda_link1,0.0,-0.08,0.0,0"),
                  srdf_, {Csv() + ":3", "radius must be > 0"});
  ExpectLoadError(urdf_,
                  Edit(csv_, "panda_link1,0.0,-0.08,0.0,0.06", "panda_link1,0.0,-0.08,0.0,nan"),
                  srdf_, {Csv() + ":3", "radius 'nan'"});
  ExpectLoadError(urdf_, Edit(csv_, "link,x,y,z,radius\n", ""), srdf_,
                  {Csv() + ":1", "header 'link,x,y,z,radius'"});
  ExpectLoadError(urdf_, "link,x,y,z,radius\n", srdf_, {Csv(), "no sphere rows"});
}

TEST_F(PandaBadInput, SrdfErrors) {
  ExpectLoadError(urdf_, csv_,
                  Edit(srdf_, "link1=\"panda_link0\" link2=\"panda_link2\"",
                       "link1=\"panda_link0\" link2=\"panda_link22\""),
                  {Srdf() + ":52", "unknown link 'panda_link22'"});
  ExpectLoadError(
      urdf_, csv_,
      Edit(srdf_, "link1=\"panda_link0\" link2=\"panda_link2\"", "link1=\"panda_link0\""),
      {Srdf() + ":52", "link1 and link2"});
  ExpectLoadError(urdf_, csv_, "<robot><disable_collisions link1=\"a\"",
                  {Srdf() + ":1", "not valid XML"});
  ExpectLoadError(urdf_, csv_, "<robots/>", {Srdf(), "<robot>"});
}

}  // namespace
}  // namespace foresight::manipulation
