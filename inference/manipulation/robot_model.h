#pragma once
/// The Panda robot model of the manipulation runtime (thesis ch 9, GFCS): kinematic tree from a
/// URDF, joint limits, the collision-sphere model and the self-collision sphere pairs (SRDF);
/// forward kinematics of every link frame and sphere centre with their position Jacobians and the
/// acceleration bias Jdot * qdot, in fixed-size Eigen and without allocation.
///
///   const RobotModel model = RobotModel::LoadPanda(dir);  // immutable, share across threads
///   KinematicsData data = model.MakeData();                // one per caller
///   ForwardKinematicsWithJacobians(model, q, qdot, &data); // no allocation; ~1.5 us on the
///                                                          // Panda (bench_kinematics)
///   data.p_WS.col(s), data.J_WS[s], data.Jdot_qdot_WS[s]   // sphere s: x, J, Jdot qdot
///
/// Frames: W is the frame of the URDF's root link (panda_link0). Body k (k = 1..kDof) is the child
/// frame of arm joint k (see KinematicsData::X_WB); body 0 is W. Every link is rigidly attached to
/// one body: the one after the last arm joint among its ancestors (fixed joints are folded into
/// constant transforms).
///
/// Model rules (checked at load; a violation throws foresight::Error naming the file and problem):
/// - the non-fixed joints are exactly kDof revolute joints on one path from the root (the arm);
///   prismatic, continuous, floating, planar and mimic joints are rejected. panda.urdf holds the
///   fingers with fixed joints at +-0.065 m (MotionBenchMaker's finger separation, see
///   franka_panda/README.md), so they are rigid parts of the hand; a URDF with prismatic fingers
///   (franka_ros) must fix them first.
/// - every arm joint has a <limit> with lower < upper and velocity > 0, and a non-zero axis.
/// - every sphere row names a URDF link, has finite numbers and radius > 0.
/// - every SRDF <disable_collisions> names two URDF links.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "inference/manipulation/joint_types.h"

namespace foresight::manipulation {

/// [6 x kDof] geometric Jacobian of a frame: rows 0-2 the linear velocity of its origin, rows 3-5
/// its angular velocity, both in W (Pinocchio's LOCAL_WORLD_ALIGNED; KDL's default Jacobian).
using FrameJacobian = Eigen::Matrix<double, 6, kDof>;

/// Arm joint limits from the URDF, in arm-joint order.
struct JointLimits {
  JointVector lower, upper;  ///< hard position limits (rad), <limit lower upper>
  JointVector velocity;      ///< speed limits (rad/s), <limit velocity>
  /// Soft position limits (rad) from <safety_controller soft_lower_limit soft_upper_limit> (the
  /// Franka datasheet limits for the Panda); equal to lower/upper for a joint without one.
  JointVector soft_lower, soft_upper;
};

/// One collision sphere, rigidly attached to a link.
struct CollisionSphere {
  int link = -1;                                   ///< link index (RobotModel::link_name)
  std::string link_name;                           ///< as in the spheres file
  Eigen::Vector3d p_LS = Eigen::Vector3d::Zero();  ///< centre in the link frame (m)
  double radius = 0;                               ///< (m), > 0
};

/// Work buffers and results of the kinematics functions, sized once by RobotModel::MakeData().
/// One per caller; valid for the model that made it. Fields are written by the functions below
/// (the ones documented "WithJacobians" only by ForwardKinematicsWithJacobians).
struct KinematicsData {
  // ---- ForwardKinematics -------------------------------------------------------------------
  /// [num_links] pose of each link frame in W, in RobotModel link order
  std::vector<Eigen::Isometry3d> X_WL;
  Eigen::Matrix3Xd p_WS;                           ///< [3 x num_spheres] sphere centres in W (m)
  Eigen::Vector3d p_WE = Eigen::Vector3d::Zero();  ///< end-effector link origin in W (m)
  std::array<Eigen::Vector3d, kDof> z_WJ;          ///< unit axis of each arm joint in W
  std::array<Eigen::Vector3d, kDof> p_WJ;  ///< origin of each arm joint frame (on its axis), W (m)

  // ---- WithJacobians -----------------------------------------------------------------------
  /// [num_spheres] d p_WS / d q (m/rad). Columns at and after the sphere's
  /// RobotModel::num_supporting_joints are zero.
  std::vector<PointJacobian> J_WS;
  Eigen::Matrix3Xd v_WS;  ///< [3 x num_spheres] sphere-centre velocities J qdot in W (m/s)
  /// [num_spheres] (dJ/dt) qdot in W (m/s^2): the centre's acceleration when qddot = 0, so
  /// pddot = J qddot + Jdot_qdot.
  std::vector<Eigen::Vector3d> Jdot_qdot_WS;
  PointJacobian J_WE = PointJacobian::Zero();              ///< d p_WE / d q (m/rad)
  Eigen::Vector3d v_WE = Eigen::Vector3d::Zero();          ///< J_WE qdot (m/s)
  Eigen::Vector3d Jdot_qdot_WE = Eigen::Vector3d::Zero();  ///< (dJ_WE/dt) qdot (m/s^2)

  // ---- per-body state ------------------------------------------------------------------------
  /// Body frames in W: body 0 is W, body k the child frame of arm joint k up to a constant
  /// rotation that turns its z axis onto the joint axis (none for a URDF axis of +z, as on the
  /// Panda).
  std::array<Eigen::Isometry3d, kDof + 1> X_WB;
  /// WithJacobians: angular velocity, angular acceleration at qddot = 0, origin velocity and
  /// origin acceleration at qddot = 0 of each body, in W.
  std::array<Eigen::Vector3d, kDof + 1> w_WB, alpha_WB, v_WB, a_WB;

  /// Scratch of ForwardKinematicsWithJacobians: the per-point quantities are affine in the point
  /// p_W, so they are stored as matrices applied to each sphere centre.
  struct Affine {
    /// J(p) stacked column-major [21] = G p + g; rows 3i..3i+2: skew(z_i), o_i x z_i.
    Eigen::Matrix<double, 3 * kDof, 3> G;
    Eigen::Matrix<double, 3 * kDof, 1> g;
    /// Per body: (v; Jdot qdot) of a point p on it = K p + k.
    std::array<Eigen::Matrix<double, 6, 3>, kDof + 1> K;
    std::array<Eigen::Matrix<double, 6, 1>, kDof + 1> k;
  } affine;
};

/// The immutable robot model: load once, share, make one KinematicsData per caller.
class RobotModel {
 public:
  /// An empty model (no links); use Load or LoadPanda.
  RobotModel() = default;

  /// Reads the kinematic tree and limits from `urdf_path` (urdfdom), the collision spheres from
  /// `spheres_csv` (header `link,x,y,z,radius`, then one sphere per row: link name and centre in
  /// the link frame, metres; blank lines and lines starting with '#' are skipped) and the disabled
  /// link pairs from `srdf_path` (<disable_collisions link1 link2>; empty path: none).
  /// Throws foresight::Error naming the file (and line for CSV/SRDF) on any bad input.
  static RobotModel Load(const std::string& urdf_path, const std::string& spheres_csv,
                         const std::string& srdf_path);
  /// Load from texts instead of files (same formats and checks; empty `srdf`: no disabled pairs).
  /// `source` names the robot in error messages ("<source> URDF", "<source> spheres:line").
  static RobotModel FromText(const std::string& urdf, const std::string& spheres_csv,
                             const std::string& srdf, const std::string& source);
  /// Load(dir/panda.urdf, dir/spheres_vamp.csv, dir/panda.srdf), and checks that the arm joints
  /// are panda_joint1..7 in order.
  static RobotModel LoadPanda(const std::string& franka_dir);

  const std::string& name() const { return name_; }  ///< <robot name>

  // ---- joints ------------------------------------------------------------------------------
  const JointLimits& limits() const { return limits_; }
  /// [kDof] arm joint names, root to tip (the order of JointVector entries).
  const std::vector<std::string>& joint_names() const { return joint_names_; }

  // ---- links -------------------------------------------------------------------------------
  /// Links in depth-first order from the root (parents before children); link 0 is the root.
  int num_links() const { return static_cast<int>(link_names_.size()); }
  const std::string& link_name(int link) const { return link_names_[static_cast<size_t>(link)]; }
  /// Index of the link named `name`; throws foresight::Error naming it when there is none.
  int LinkIndex(const std::string& name) const;
  /// Parent link index (-1 for the root).
  int link_parent(int link) const { return link_parent_[static_cast<size_t>(link)]; }
  /// Number of arm joints that move `link` (= its body index): the first this many columns of its
  /// Jacobians can be non-zero, the rest are always zero. 0 for links fixed to the root.
  int num_supporting_joints(int link) const { return link_body_[static_cast<size_t>(link)]; }
  /// The end-effector link: panda_grasptarget when the URDF has it (the grasp target of
  /// MotionBenchMaker and the README), else the child link of the last arm joint.
  int end_effector_link() const { return ee_link_; }

  // ---- collision spheres -------------------------------------------------------------------
  int num_spheres() const { return static_cast<int>(spheres_.size()); }
  /// In the order of the spheres file.
  const std::vector<CollisionSphere>& spheres() const { return spheres_; }
  /// Sphere index pairs (i < j, sorted) to check for self-collision: spheres on links A != B such
  /// that (1) A and B are not rigidly attached (they move with different bodies: spheres of links
  /// joined only by fixed joints never change their relative pose), (2) the bodies of A and B are
  /// not adjacent (joined by one arm joint: their spheres overlap at the joint by construction, as
  /// MoveIt's "Adjacent" rule), and (3) {A, B} is not a <disable_collisions> pair of the SRDF.
  /// Panda with panda.srdf and spheres_vamp.csv: 690 pairs.
  const std::vector<std::pair<int, int>>& self_collision_pairs() const {
    return self_collision_pairs_;
  }
  /// Whether the SRDF disabled collisions between links a and b (symmetric).
  bool CollisionDisabled(int link_a, int link_b) const;

  /// Buffers for the kinematics functions, sized for this model (allocates; call once).
  KinematicsData MakeData() const;

 private:
  friend void ForwardKinematics(const RobotModel&, const JointVector&, KinematicsData*);
  friend void ForwardKinematicsWithJacobians(const RobotModel&, const JointVector&,
                                             const JointVector&, KinematicsData*);
  /// Load and FromText: the names (paths) prefix error messages; srdf_text null: no SRDF.
  static RobotModel FromTexts(const std::string& urdf_text, const std::string& urdf_name,
                              const std::string& spheres_text, const std::string& spheres_name,
                              const std::string* srdf_text, const std::string& srdf_name);

  std::string name_;
  std::vector<std::string> joint_names_;
  JointLimits limits_;
  // Arm joint k: its frame at q = 0 in body k, rotated so that its z axis is the joint axis.
  std::array<Eigen::Isometry3d, kDof> X_BJ_;
  // Links: name, parent, body index and the constant pose in their body frame.
  std::vector<std::string> link_names_;
  std::vector<int> link_parent_, link_body_;
  std::vector<Eigen::Isometry3d> X_BL_;
  std::vector<char> disabled_;  // [num_links^2] SRDF-disabled link pairs
  // Spheres: public description, and body index and centre in the body frame (hot path).
  std::vector<CollisionSphere> spheres_;
  std::vector<int> sphere_body_;
  Eigen::Matrix3Xd p_BS_;
  std::array<std::vector<int>, kDof + 1> spheres_on_body_;
  std::vector<std::pair<int, int>> self_collision_pairs_;
  int ee_link_ = -1, ee_body_ = 0;
  Eigen::Vector3d p_BE_ = Eigen::Vector3d::Zero();
};

/// Link frames, sphere centres and the end-effector position at `q`; also the per-body poses and
/// joint axes (z_WJ, p_WJ). No allocation.
/// @param q [kDof] arm joint angles (rad); not checked against the limits.
/// @param data from model.MakeData().
void ForwardKinematics(const RobotModel& model, const JointVector& q, KinematicsData* data);

/// ForwardKinematics plus, for every sphere centre and the end effector, the position Jacobian J,
/// the velocity J qdot and the acceleration bias Jdot qdot. No allocation.
/// Column i of a point p's Jacobian is z_i x (p - o_i) for the arm joints i that move it (axis z_i
/// through o_i, in W). Jdot qdot is the point's acceleration at qddot = 0, from the
/// standard body recursion (angular velocity w, angular acceleration alpha, origin velocity v and
/// acceleration a of each body; e.g. Featherstone, Rigid Body Dynamics Algorithms, ch. 2): for a
/// point p on body b with r = p - o_b,
///   pdot = v_b + w_b x r,  Jdot qdot = a_b + alpha_b x r + w_b x (w_b x r),
/// which equals sum_i qdot_i [(w_i x z_i) x (p - o_i) + z_i x (pdot - odot_i)], the column-wise
/// derivative (w_i the angular velocity of joint i's parent body).
/// @param q [kDof] arm joint angles (rad)
/// @param qdot [kDof] arm joint velocities (rad/s)
void ForwardKinematicsWithJacobians(const RobotModel& model, const JointVector& q,
                                    const JointVector& qdot, KinematicsData* data);

/// Geometric Jacobian of link `link`'s frame (origin velocity and angular velocity in W), from the
/// data of a previous ForwardKinematics* call at the same q. No allocation.
void LinkJacobian(const RobotModel& model, const KinematicsData& data, int link, FrameJacobian* J);

}  // namespace foresight::manipulation
