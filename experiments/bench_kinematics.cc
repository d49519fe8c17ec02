// Panda kinematics side by side with KDL in one run: positions, and positions + Jacobians (+ the
// acceleration bias Jdot qdot) of all 59 collision spheres and the grasp target. KDL chains are
// built from the same URDF (as kdl_parser does), one per sphere with the centre as a last fixed
// segment. Target (issue): ours with Jacobians and Jdot qdot <= 3 us.
//   FORESIGHT_SOURCE_DIR=/path/to/main bench_kinematics --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
// (the Panda files are read from $FORESIGHT_SOURCE_DIR/../shared/data/franka_panda, default ".").

#include <benchmark/benchmark.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/jntarrayvel.hpp>
#include <memory>
#include <random>
#include <vector>

#include "inference/manipulation/robot_model.h"

namespace foresight::manipulation {
namespace {

std::string FrankaDir() {
  const char* root = std::getenv("FORESIGHT_SOURCE_DIR");
  return (std::filesystem::path(root ? root : ".") / ".." / "shared" / "data" / "franka_panda")
      .string();
}

const RobotModel& Model() {
  static const RobotModel model = RobotModel::LoadPanda(FrankaDir());
  return model;
}

/// 64 random (q, qdot) within the limits, cycled through by every benchmark.
struct States {
  std::vector<JointVector> q, qdot;
};
const States& RandomStates() {
  static const States states = [] {
    States s;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0, 1);
    const JointLimits& l = Model().limits();
    for (int k = 0; k < 64; ++k) {
      JointVector q, qdot;
      for (int i = 0; i < kDof; ++i) {
        q[i] = l.lower[i] + u(rng) * (l.upper[i] - l.lower[i]);
        qdot[i] = (2 * u(rng) - 1) * l.velocity[i];
      }
      s.q.push_back(q);
      s.qdot.push_back(qdot);
    }
    return s;
  }();
  return states;
}

// ---- KDL ------------------------------------------------------------------------------------

KDL::Frame ToKdl(const urdf::Pose& p) {
  return KDL::Frame(
      KDL::Rotation::Quaternion(p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w),
      KDL::Vector(p.position.x, p.position.y, p.position.z));
}

/// Root -> `tip` link (-> optional point in the tip frame), with its solvers.
struct KdlChain {
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jac;
  std::unique_ptr<KDL::ChainJntToJacDotSolver> jac_dot;
  KDL::JntArray q;
  KDL::JntArrayVel qv;
  KDL::Jacobian J;

  KdlChain(const urdf::ModelInterface& urdf, const std::string& tip, const Eigen::Vector3d* p) {
    std::vector<urdf::JointConstSharedPtr> joints;
    for (auto link = urdf.getLink(tip); link->parent_joint;
         link = urdf.getLink(link->parent_joint->parent_link_name))
      joints.insert(joints.begin(), link->parent_joint);
    for (const auto& j : joints) {
      const KDL::Frame F = ToKdl(j->parent_to_joint_origin_transform);
      chain.addSegment(KDL::Segment(
          j->child_link_name,
          j->type == urdf::Joint::FIXED
              ? KDL::Joint(j->name, KDL::Joint::Fixed)
              : KDL::Joint(j->name, F.p, F.M * KDL::Vector(j->axis.x, j->axis.y, j->axis.z),
                           KDL::Joint::RotAxis),
          F));
    }
    if (p != nullptr)
      chain.addSegment(KDL::Segment("point", KDL::Joint(KDL::Joint::Fixed),
                                    KDL::Frame(KDL::Vector((*p)[0], (*p)[1], (*p)[2]))));
    fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(chain);
    jac = std::make_unique<KDL::ChainJntToJacSolver>(chain);
    jac_dot = std::make_unique<KDL::ChainJntToJacDotSolver>(chain);
    q.resize(chain.getNrOfJoints());
    qv.q.resize(chain.getNrOfJoints());
    qv.qdot.resize(chain.getNrOfJoints());
    J.resize(chain.getNrOfJoints());
  }
  void Set(const JointVector& q_in, const JointVector& qdot_in) {
    for (unsigned i = 0; i < q.rows(); ++i) {
      q(i) = qv.q(i) = q_in[i];
      qv.qdot(i) = qdot_in[i];
    }
  }
};

/// One chain per sphere (centre as the tip) and one to the grasp target.
struct KdlSpheres {
  std::vector<std::unique_ptr<KdlChain>> chains;
  KdlSpheres() {
    const RobotModel& model = Model();
    const auto urdf = urdf::parseURDFFile(FrankaDir() + "/panda.urdf");
    for (const CollisionSphere& s : model.spheres())
      chains.push_back(std::make_unique<KdlChain>(*urdf, s.link_name, &s.p_LS));
    chains.push_back(
        std::make_unique<KdlChain>(*urdf, model.link_name(model.end_effector_link()), nullptr));
  }
};

// ---- benchmarks ---------------------------------------------------------------------------------

void BM_Ours_Positions(benchmark::State& state) {
  const RobotModel& model = Model();
  const States& s = RandomStates();
  KinematicsData data = model.MakeData();
  size_t k = 0;
  for (auto _ : state) {
    ForwardKinematics(model, s.q[k++ % s.q.size()], &data);
    benchmark::DoNotOptimize(data.p_WS.data());
  }
}
BENCHMARK(BM_Ours_Positions);

void BM_Ours_PositionsJacobiansJdotQdot(benchmark::State& state) {
  const RobotModel& model = Model();
  const States& s = RandomStates();
  KinematicsData data = model.MakeData();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ % s.q.size();
    ForwardKinematicsWithJacobians(model, s.q[i], s.qdot[i], &data);
    benchmark::DoNotOptimize(data.J_WS.data());
    benchmark::DoNotOptimize(data.Jdot_qdot_WS.data());
  }
}
BENCHMARK(BM_Ours_PositionsJacobiansJdotQdot);

void BM_Kdl_Positions(benchmark::State& state) {
  KdlSpheres kdl;
  const States& s = RandomStates();
  KDL::Frame f;
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ % s.q.size();
    for (auto& c : kdl.chains) {
      c->Set(s.q[i], s.qdot[i]);
      c->fk->JntToCart(c->q, f);
      benchmark::DoNotOptimize(f.p.data);
    }
  }
}
BENCHMARK(BM_Kdl_Positions);

void BM_Kdl_PositionsJacobians(benchmark::State& state) {
  KdlSpheres kdl;
  const States& s = RandomStates();
  KDL::Frame f;
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ % s.q.size();
    for (auto& c : kdl.chains) {
      c->Set(s.q[i], s.qdot[i]);
      c->fk->JntToCart(c->q, f);
      c->jac->JntToJac(c->q, c->J);
      benchmark::DoNotOptimize(f.p.data);
      benchmark::DoNotOptimize(c->J.data.data());
    }
  }
}
BENCHMARK(BM_Kdl_PositionsJacobians);

void BM_Kdl_PositionsJacobiansJdotQdot(benchmark::State& state) {
  KdlSpheres kdl;
  const States& s = RandomStates();
  KDL::Frame f;
  KDL::Twist jdot_qdot;
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ % s.q.size();
    for (auto& c : kdl.chains) {
      c->Set(s.q[i], s.qdot[i]);
      c->fk->JntToCart(c->q, f);
      c->jac->JntToJac(c->q, c->J);
      c->jac_dot->JntToJacDot(c->qv, jdot_qdot);
      benchmark::DoNotOptimize(f.p.data);
      benchmark::DoNotOptimize(c->J.data.data());
      benchmark::DoNotOptimize(jdot_qdot.vel.data);
    }
  }
}
BENCHMARK(BM_Kdl_PositionsJacobiansJdotQdot);

/// KDL used economically: one Jacobian per link that carries spheres (and the grasp target),
/// moved to each sphere centre with changeRefPoint; sphere centres from the link frames.
void BM_Kdl_PerLinkJacobiansRefPoint(benchmark::State& state) {
  const RobotModel& model = Model();
  const auto urdf = urdf::parseURDFFile(FrankaDir() + "/panda.urdf");
  std::vector<int> links;  // links with spheres, then the end effector
  for (const CollisionSphere& s : model.spheres())
    if (std::find(links.begin(), links.end(), s.link) == links.end()) links.push_back(s.link);
  links.push_back(model.end_effector_link());
  std::vector<std::unique_ptr<KdlChain>> chains;
  for (const int l : links)
    chains.push_back(std::make_unique<KdlChain>(*urdf, model.link_name(l), nullptr));
  std::vector<size_t> chain_of(model.spheres().size());
  for (size_t s = 0; s < chain_of.size(); ++s)
    chain_of[s] = static_cast<size_t>(
        std::find(links.begin(), links.end(), model.spheres()[s].link) - links.begin());
  std::vector<KDL::Frame> frames(chains.size());
  KDL::Jacobian J_sphere(kDof);
  const States& st = RandomStates();
  size_t k = 0;
  for (auto _ : state) {
    const size_t i = k++ % st.q.size();
    for (size_t c = 0; c < chains.size(); ++c) {
      chains[c]->Set(st.q[i], st.qdot[i]);
      chains[c]->fk->JntToCart(chains[c]->q, frames[c]);
      chains[c]->jac->JntToJac(chains[c]->q, chains[c]->J);
    }
    for (size_t s = 0; s < chain_of.size(); ++s) {
      const KDL::Frame& X = frames[chain_of[s]];
      const Eigen::Vector3d& p = model.spheres()[s].p_LS;
      const KDL::Vector p_W = X * KDL::Vector(p[0], p[1], p[2]);
      J_sphere.resize(chains[chain_of[s]]->J.columns());
      KDL::changeRefPoint(chains[chain_of[s]]->J, p_W - X.p, J_sphere);
      benchmark::DoNotOptimize(p_W.data);
      benchmark::DoNotOptimize(J_sphere.data.data());
    }
  }
}
BENCHMARK(BM_Kdl_PerLinkJacobiansRefPoint);

}  // namespace
}  // namespace foresight::manipulation

int main(int argc, char** argv) {
  try {
    foresight::manipulation::Model();
  } catch (const std::exception& e) {
    std::cerr << "bench_kinematics: " << e.what() << "\n";
    return 1;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
