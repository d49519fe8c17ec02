// The serial chain against independent computations: KDL chains built from the same URDF by hand
// (kdl_parser is not packaged), central finite differences, the README's numbers, a brute-force
// check of the ball cover, and bad input. JACO tests skip without ../shared/data; the synthetic
// chain (tilted axes, fixed joints in the chain, a base link below the root, an off-chain finger)
// always runs.

#include "inference/imitation/serial_chain.h"

#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using foresight::testing::ExpectErrorContains;
using foresight::testing::MatricesNear;
using foresight::testing::ReadText;

std::string JacoDir() {
  const std::string data = foresight::testing::SharedDataDir();
  return data.empty() ? "" : data + "/kinova_jaco_j2n6s300";
}

#define SKIP_WITHOUT_JACO()                                                                    \
  const std::string jaco = JacoDir();                                                          \
  if (jaco.empty())                                                                            \
  GTEST_SKIP() << "../shared/data (kinova_jaco_j2n6s300) is absent: set FORESIGHT_SOURCE_DIR " \
                  "to the repository root next to shared/"

// A 6-DoF arm below a fixed `world` root: tilted and negative axes, rotated joint origins, fixed
// joints inside the chain, one continuous joint without <limit>, and a revolute finger off the
// chain (ignored).
const char* kSyntheticUrdf = R"(<?xml version="1.0"?>
<robot name="synthetic">
  <link name="world"/><link name="base"/><link name="l1"/><link name="l2"/><link name="l2b"/>
  <link name="l3"/><link name="l4"/><link name="l5"/><link name="l6"/><link name="tool"/>
  <link name="finger"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/>
    <origin xyz="0.3 -0.2 0.1" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.12" rpy="0 0 0.4"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.02 0 0.1" rpy="1.5707963 0 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="elbow_offset" type="fixed"><parent link="l2"/><child link="l2b"/>
    <origin xyz="0.35 0.01 0" rpy="0 0.3 0"/></joint>
  <joint name="j3" type="continuous"><parent link="l2b"/><child link="l3"/>
    <origin xyz="0.05 0 0" rpy="0 0 0.2"/><axis xyz="0 0 -1"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.3 0 0" rpy="0 1.5707963 0"/><axis xyz="1 0 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j5" type="continuous"><parent link="l4"/><child link="l5"/>
    <origin xyz="0 0 0.1" rpy="-0.5 0 0"/><axis xyz="0.3 -0.4 0.866"/>
    <limit lower="-6" upper="6" effort="1" velocity="1"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/>
    <origin xyz="0 0.08 0.02" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="l6"/><child link="tool"/>
    <origin xyz="0 0 0.12" rpy="3.14159 0 0"/></joint>
  <joint name="finger_joint" type="revolute"><parent link="l6"/><child link="finger"/>
    <origin xyz="0.02 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="2" effort="1" velocity="1"/></joint>
</robot>
)";

std::vector<BodyPoint> SyntheticPoints() {
  return {{"base", {0.01, 0.02, 0.03}, 0.05}, {"l1", {0.0, 0.05, 0.05}, 0.04},
          {"l2", {0.2, 0.0, 0.01}, 0.04},     {"l2b", {0.0, 0.02, 0.0}, 0.03},
          {"l3", {0.15, 0.0, -0.02}, 0.04},   {"l4", {0.0, 0.01, 0.05}, 0.03},
          {"l5", {0.01, 0.0, 0.0}, 0.03},     {"l6", {0.0, 0.0, 0.06}, 0.03},
          {"tool", {0.0, 0.01, 0.02}, 0.02}};
}

SerialChain SyntheticChain() {
  return SerialChain::FromText(kSyntheticUrdf, "synthetic.urdf", "base", "tool", SyntheticPoints());
}

// ---- independent reference: KDL chains from urdfdom ------------------------------------------

KDL::Frame ToKdl(const urdf::Pose& pose) {
  return KDL::Frame(
      KDL::Rotation::Quaternion(pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w),
      KDL::Vector(pose.position.x, pose.position.y, pose.position.z));
}

/// The KDL chain from `base` to a point `offset` in link `tip`, with segments as kdl_parser makes
/// them (joint about the axis in the parent frame through the joint origin, then the origin).
struct KdlPoint {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;

  KdlPoint(const urdf::ModelInterface& urdf, const std::string& base, const std::string& tip,
           const Eigen::Vector3d& offset) {
    std::vector<urdf::JointConstSharedPtr> joints;
    for (auto link = urdf.getLink(tip); link->name != base;
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
    chain.addSegment(KDL::Segment("point", KDL::Joint(KDL::Joint::Fixed),
                                  KDL::Frame(KDL::Vector(offset[0], offset[1], offset[2]))));
    fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(chain);
    jac = std::make_unique<KDL::ChainJntToJacSolver>(chain);
  }
  KDL::JntArray Head(const ArmVector& q) const {
    KDL::JntArray out(chain.getNrOfJoints());
    for (unsigned i = 0; i < chain.getNrOfJoints(); ++i) out(i) = q[static_cast<int>(i)];
    return out;
  }
  Eigen::Vector3d Position(const ArmVector& q) const {
    KDL::Frame f;
    EXPECT_GE(fk->JntToCart(Head(q), f), 0);
    return {f.p(0), f.p(1), f.p(2)};
  }
  PointJacobian6 Jacobian(const ArmVector& q) const {
    KDL::Jacobian J(chain.getNrOfJoints());
    EXPECT_GE(jac->JntToJac(Head(q), J), 0);
    PointJacobian6 out = PointJacobian6::Zero();
    for (unsigned i = 0; i < chain.getNrOfJoints(); ++i)
      out.col(static_cast<int>(i)) = J.data.col(i).head<3>();
    return out;
  }
};

ArmVector RandomConfiguration(const SerialChain& chain, std::mt19937_64* rng) {
  ArmVector q;
  for (int k = 0; k < kArmDof; ++k) {
    const double lo = std::max(chain.lower()[k], -M_PI), hi = std::min(chain.upper()[k], M_PI);
    q[k] = std::uniform_real_distribution<double>(lo, hi)(*rng);
  }
  return q;
}

/// Every body point, the end effector and their Jacobians against KDL on random configurations.
void ExpectMatchesKdl(const SerialChain& chain, const std::string& urdf_text, int trials) {
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(urdf_text);
  ASSERT_NE(urdf, nullptr);
  std::vector<std::unique_ptr<KdlPoint>> reference;
  for (const BodyPoint& point : chain.points())
    reference.push_back(
        std::make_unique<KdlPoint>(*urdf, chain.base_link(), point.link, point.offset));
  const KdlPoint tip(*urdf, chain.base_link(), chain.tip_link(), Eigen::Vector3d::Zero());
  ChainData data = chain.MakeData();
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < trials; ++trial) {
    const ArmVector q = RandomConfiguration(chain, &rng);
    Kinematics(chain, q, &data);
    for (int j = 0; j < chain.num_points(); ++j) {
      SCOPED_TRACE("point " + std::to_string(j) + " on " + chain.points()[j].link);
      EXPECT_TRUE(MatricesNear(data.p.col(j), reference[j]->Position(q), 1e-10));
      EXPECT_TRUE(MatricesNear(data.J[j], reference[j]->Jacobian(q), 1e-10));
    }
    EXPECT_TRUE(MatricesNear(data.p_ee, tip.Position(q), 1e-10));
    EXPECT_TRUE(MatricesNear(data.J_ee, tip.Jacobian(q), 1e-10));
  }
}

/// Jacobians of every point and of the end effector against central differences of Kinematics.
void ExpectJacobiansMatchFiniteDifferences(const SerialChain& chain) {
  ChainData data = chain.MakeData(), plus = chain.MakeData(), minus = chain.MakeData();
  std::mt19937_64 rng(5);
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 5; ++trial) {
    const ArmVector q = RandomConfiguration(chain, &rng);
    Kinematics(chain, q, &data);
    for (int k = 0; k < kArmDof; ++k) {
      const ArmVector e = ArmVector::Unit(k) * h;
      Kinematics(chain, q + e, &plus);
      Kinematics(chain, q - e, &minus);
      for (int j = 0; j < chain.num_points(); ++j)
        EXPECT_TRUE(
            MatricesNear(data.J[j].col(k), (plus.p.col(j) - minus.p.col(j)) / (2 * h), 1e-8))
            << "point " << j << " joint " << k;
      EXPECT_TRUE(MatricesNear(data.J_ee.col(k), (plus.p_ee - minus.p_ee) / (2 * h), 1e-8));
    }
  }
}

/// phi(x) = exp(-||x - c||^2 / s^2) with its gradient and Hessian (closed form).
struct GaussianBump {
  Eigen::Vector3d c;
  double s;
  double operator()(const Eigen::Vector3d& x, Eigen::Vector3d* g, Eigen::Matrix3d* H) const {
    const Eigen::Vector3d d = x - c;
    const double v = std::exp(-d.squaredNorm() / (s * s));
    *g = -2 * v / (s * s) * d;
    *H = v * (4 / (s * s * s * s) * d * d.transpose() - 2 / (s * s) * Eigen::Matrix3d::Identity());
    return v;
  }
};

/// sum_j phi(x_j(q)) by Kinematics; grad and Hess by AddPointPotential.
double Potential(const SerialChain& chain, const GaussianBump& bump, const ArmVector& q,
                 ChainData* data, ArmVector* grad, ArmMatrix* hess) {
  Kinematics(chain, q, data);
  grad->setZero();
  if (hess != nullptr) hess->setZero();
  double total = 0;
  for (int j = 0; j < chain.num_points(); ++j) {
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    total += bump(data->p.col(j), &g, &H);
    AddPointPotential(*data, j, g, H, grad, hess);
  }
  return total;
}

/// V = grad_q sum_j phi(x_j) against differences of the sum, dV against differences of V.
void ExpectPotentialDerivativesMatchFiniteDifferences(const SerialChain& chain,
                                                      const GaussianBump& bump) {
  ChainData data = chain.MakeData();
  std::mt19937_64 rng(17);
  int informative = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const ArmVector q = RandomConfiguration(chain, &rng);
    ArmVector V, Vp, Vm;
    ArmMatrix dV, scratch;
    Potential(chain, bump, q, &data, &V, &dV);
    if (V.norm() > 1e-3) ++informative;
    constexpr double h = 1e-5;
    ArmVector V_fd;
    ArmMatrix dV_fd;
    for (int k = 0; k < kArmDof; ++k) {
      const ArmVector e = ArmVector::Unit(k) * h;
      const double fp = Potential(chain, bump, q + e, &data, &Vp, &scratch);
      const double fm = Potential(chain, bump, q - e, &data, &Vm, &scratch);
      V_fd[k] = (fp - fm) / (2 * h);
      dV_fd.col(k) = (Vp - Vm) / (2 * h);
    }
    const double scale = 1 + dV.cwiseAbs().maxCoeff();
    EXPECT_TRUE(MatricesNear(V, V_fd, 1e-8 * (1 + V.cwiseAbs().maxCoeff())));
    EXPECT_TRUE(MatricesNear(dV, dV_fd, 1e-6 * scale));
    EXPECT_TRUE(MatricesNear(dV, dV.transpose(), 1e-12 * scale)) << "a Hessian is symmetric";
  }
  EXPECT_GE(informative, 4) << "the bump should touch the arm in most trials";
}

// ---- JACO ------------------------------------------------------------------------------------

TEST(JacoChain, JointsLimitsAndPointsMatchTheReadme) {
  SKIP_WITHOUT_JACO();
  const SerialChain chain = SerialChain::LoadJaco(jaco);
  EXPECT_EQ(chain.base_link(), "base");
  EXPECT_EQ(chain.tip_link(), "j2n6s300_end_effector");
  for (int k = 0; k < kArmDof; ++k) {
    EXPECT_EQ(chain.joint_names()[k], "j2n6s300_joint_" + std::to_string(k + 1));
    const bool continuous = k != 1 && k != 2;
    EXPECT_EQ(chain.continuous(k), continuous) << k;
    EXPECT_NEAR(chain.lower()[k], continuous ? -2 * M_PI : -2.618, 1e-9) << k;
    EXPECT_NEAR(chain.upper()[k], continuous ? 2 * M_PI : 2.613, 1e-9) << k;
  }
  EXPECT_EQ(chain.num_points(), 12);
  EXPECT_EQ(chain.points().back().link, "j2n6s300_end_effector");
  // Fingers are off the chain: never a chain link.
  for (const auto& link : chain.chain_links()) EXPECT_EQ(link.find("finger"), std::string::npos);
}

TEST(JacoChain, EndEffectorMatchesTheReadme) {
  SKIP_WITHOUT_JACO();
  const SerialChain chain = SerialChain::LoadJaco(jaco);
  ChainData data = chain.MakeData();
  Kinematics(chain, ArmVector::Zero(), &data);
  EXPECT_TRUE(MatricesNear(data.p_ee, Eigen::Vector3d(0.0001, 0.0643, 1.1811), 1e-4));
  ArmVector folded = ArmVector::Zero();
  folded[1] = folded[2] = M_PI;
  Kinematics(chain, folded, &data);
  EXPECT_NEAR(data.p_ee.z(), 0.361, 1e-3);
}

TEST(JacoChain, ForwardKinematicsMatchesKdl) {
  SKIP_WITHOUT_JACO();
  const SerialChain chain = SerialChain::LoadJaco(jaco);
  ExpectMatchesKdl(chain, ReadText(jaco + "/j2n6s300.urdf"), 20);
}

TEST(JacoChain, JacobiansMatchFiniteDifferences) {
  SKIP_WITHOUT_JACO();
  ExpectJacobiansMatchFiniteDifferences(SerialChain::LoadJaco(jaco));
}

TEST(JacoChain, PotentialHessianMatchesFiniteDifferences) {
  SKIP_WITHOUT_JACO();
  // A bump of width 0.3 m around the upper arm's reach: most random arms pass through it.
  ExpectPotentialDerivativesMatchFiniteDifferences(SerialChain::LoadJaco(jaco),
                                                   {Eigen::Vector3d(0.1, 0.05, 0.55), 0.3});
}

TEST(JacoChain, BallsCoverTheCollisionCylinders) {
  SKIP_WITHOUT_JACO();
  // Brute force: points sampled in every collision cylinder of links 1-6 (read from the file)
  // lie in a ball on the same link.
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(ReadText(jaco + "/j2n6s300.urdf"));
  ASSERT_NE(urdf, nullptr);
  const std::vector<BodyPoint> balls = SerialChain::JacoBodyPoints();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  int cylinders = 0;
  for (int i = 1; i <= 6; ++i) {
    const std::string name = "j2n6s300_link_" + std::to_string(i);
    const auto link = urdf->getLink(name);
    for (const auto& collision : link->collision_array) {
      const auto* cylinder = dynamic_cast<const urdf::Cylinder*>(collision->geometry.get());
      ASSERT_NE(cylinder, nullptr) << name;
      ++cylinders;
      const urdf::Pose& pose = collision->origin;
      const Eigen::Quaterniond R(pose.rotation.w, pose.rotation.x, pose.rotation.y,
                                 pose.rotation.z);
      const Eigen::Vector3d c(pose.position.x, pose.position.y, pose.position.z);
      for (int s = 0; s < 500; ++s) {
        const double radius = cylinder->radius * std::sqrt(u(rng)), angle = 2 * M_PI * u(rng);
        const Eigen::Vector3d local(radius * std::cos(angle), radius * std::sin(angle),
                                    cylinder->length * (u(rng) - 0.5));
        const Eigen::Vector3d x = c + R * local;
        bool covered = false;
        for (const BodyPoint& b : balls)
          covered |= b.link == name && (x - b.offset).norm() <= b.radius + 1e-12;
        ASSERT_TRUE(covered) << name << " point " << x.transpose();
      }
    }
  }
  EXPECT_EQ(cylinders, 6);
}

TEST(JacoChain, InverseKinematicsReachesRandomReachableTargets) {
  SKIP_WITHOUT_JACO();
  const SerialChain chain = SerialChain::LoadJaco(jaco);
  ChainData data = chain.MakeData();
  std::mt19937_64 rng(23);
  std::normal_distribution<double> noise(0, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    const ArmVector q_true = RandomConfiguration(chain, &rng);
    Kinematics(chain, q_true, &data);
    const Eigen::Vector3d target = data.p_ee;
    ArmVector q_init = q_true;
    for (int k = 0; k < kArmDof; ++k) q_init[k] += noise(rng);
    ArmVector q;
    ASSERT_TRUE(InverseKinematics(chain, target, q_init, &q)) << "trial " << trial;
    Kinematics(chain, q, &data);
    EXPECT_LE((data.p_ee - target).norm(), 1e-6);
    EXPECT_TRUE(((q - chain.lower()).array() >= 0).all() &&
                ((chain.upper() - q).array() >= 0).all());
  }
  // Out of reach (the arm is ~1.1 m long): false, with the last iterate still finite.
  ArmVector q;
  EXPECT_FALSE(InverseKinematics(chain, Eigen::Vector3d(3, 0, 0.5), ArmVector::Zero(), &q));
  EXPECT_TRUE(q.allFinite());
}

// ---- synthetic chain (always runs) ------------------------------------------------------------

TEST(SyntheticChain, FoldsFixedJointsAndIgnoresOffChainJoints) {
  const SerialChain chain = SyntheticChain();
  const std::vector<std::string> links = {"base", "l1", "l2", "l2b", "l3",
                                          "l4",   "l5", "l6", "tool"};
  EXPECT_EQ(chain.chain_links(), links);
  EXPECT_EQ(chain.joint_names()[2], "j3");
  EXPECT_TRUE(chain.continuous(2));
  EXPECT_TRUE(std::isinf(chain.lower()[2]) && chain.lower()[2] < 0) << "no <limit>: unbounded";
  EXPECT_TRUE(std::isinf(chain.upper()[2]) && chain.upper()[2] > 0);
  EXPECT_DOUBLE_EQ(chain.lower()[4], -6);  // continuous with a <limit>: the file's
  EXPECT_DOUBLE_EQ(chain.upper()[3], 2.5);
  // Points on base / l1 / l2b are moved by 0 / 1 / 2 joints.
  EXPECT_EQ(chain.point_body(0), 0);
  EXPECT_EQ(chain.point_body(1), 1);
  EXPECT_EQ(chain.point_body(3), 2);
  EXPECT_EQ(chain.point_body(8), 6);
}

TEST(SyntheticChain, ForwardKinematicsMatchesKdl) {
  ExpectMatchesKdl(SyntheticChain(), kSyntheticUrdf, 20);
}

TEST(SyntheticChain, JacobiansMatchFiniteDifferences) {
  ExpectJacobiansMatchFiniteDifferences(SyntheticChain());
}

TEST(SyntheticChain, PotentialHessianMatchesFiniteDifferences) {
  ExpectPotentialDerivativesMatchFiniteDifferences(SyntheticChain(),
                                                   {Eigen::Vector3d(0.4, -0.1, 0.4), 0.35});
}

TEST(SyntheticChain, InverseKinematicsReachesRandomReachableTargets) {
  const SerialChain chain = SyntheticChain();
  ChainData data = chain.MakeData();
  std::mt19937_64 rng(29);
  std::normal_distribution<double> noise(0, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    const ArmVector q_true = RandomConfiguration(chain, &rng);
    Kinematics(chain, q_true, &data);
    const Eigen::Vector3d target = data.p_ee;
    ArmVector q_init = q_true;
    for (int k = 0; k < kArmDof; ++k) q_init[k] += noise(rng);
    ArmVector q;
    ASSERT_TRUE(InverseKinematics(chain, target, q_init, &q)) << "trial " << trial;
    Kinematics(chain, q, &data);
    EXPECT_LE((data.p_ee - target).norm(), 1e-6);
  }
}

// ---- bad input --------------------------------------------------------------------------------

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(SerialChainErrors, NameTheFileJointOrLink) {
  const std::string urdf = kSyntheticUrdf;
  const auto load = [](const std::string& text, const std::string& base, const std::string& tip,
                       std::vector<BodyPoint> points) {
    return [=] { SerialChain::FromText(text, "arm.urdf", base, tip, points); };
  };
  ExpectErrorContains(load("<robot", "base", "tool", {}), {"arm.urdf", "not a valid URDF"});
  ExpectErrorContains(load(urdf, "base", "gripper", {}), {"arm.urdf", "no link 'gripper'"});
  ExpectErrorContains(load(urdf, "l3", "l1", {}), {"arm.urdf", "'l3' is not an ancestor"});
  // Five arm joints up to l5; seven when the off-chain finger is the tip.
  ExpectErrorContains(load(urdf, "base", "l5", {}), {"arm.urdf", "expected 6", "found 5", "j5"});
  ExpectErrorContains(load(urdf, "world", "finger", {}),
                      {"arm.urdf", "joint 'finger_joint'", "expected exactly 6"});
  ExpectErrorContains(
      load(Replace(urdf, R"(name="j4" type="revolute")", R"(name="j4" type="prismatic")"), "base",
           "tool", {}),
      {"arm.urdf", "joint 'j4'", "prismatic"});
  ExpectErrorContains(load(urdf, "base", "tool", {{"finger", Eigen::Vector3d::Zero(), 0.01}}),
                      {"arm.urdf", "body point 0", "'finger'", "not on the chain"});
  ExpectErrorContains(load(urdf, "base", "tool", {{"l2", Eigen::Vector3d::Zero(), -1}}),
                      {"arm.urdf", "body point 0", "radius"});
  // Found by fuzz_urdf (tests/fuzz/corpus/urdf/regress_joint_loop): urdfdom accepts a loop of
  // joints off the root's tree (l3 <-> l4 here), and the walk up from the tip never ended.
  ExpectErrorContains(load(Replace(urdf, R"(type="continuous"><parent link="l2b"/>)",
                                   R"(type="continuous"><parent link="l4"/>)"),
                           "base", "tool", {}),
                      {"arm.urdf", "form a loop through link 'l4'"});
  ExpectErrorContains([] { SerialChain::Load("/nonexistent/arm.urdf", "a", "b", {}); },
                      {"/nonexistent/arm.urdf"});
  ExpectErrorContains([] { SerialChain::LoadJaco("/nonexistent"); },
                      {"/nonexistent/j2n6s300.urdf"});
}

}  // namespace
}  // namespace foresight::imitation
