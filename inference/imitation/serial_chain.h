#pragma once
/// A 6-DoF serial arm read from a URDF (the Kinova JACO2 j2n6s300 of thesis ch 8, "Building
/// Infinitesimal Generators for Collision Avoidance in C-space"): forward kinematics of body points
/// (balls on the links) and of the end effector with their position Jacobians, the pull-back of a
/// point potential's gradient and Hessian to C-space, and damped-least-squares inverse kinematics.
///
///   const SerialChain chain = SerialChain::LoadJaco(dir);  // immutable, share across threads
///   ChainData data = chain.MakeData();                      // one per caller
///   Kinematics(chain, q, &data);                            // no allocation
///   data.p.col(j), data.J[j], data.p_ee, data.J_ee          // body point j, end effector
///
/// Frames: W is the frame of the chain's base link (the URDF root for LoadJaco: `base`, or `root`
/// when the file has it). Body k (k = 1..6) is the frame of arm joint k rotated by q_k; body 0 is
/// W. Every link on the chain is rigidly attached to the body after the last arm joint above it
/// (fixed joints are folded into constant transforms).
///
/// Kinematics (URDF convention: joint k at its origin X_k in body k-1, rotating about its unit
/// axis a_k given in the joint frame):
///   X_W(k) = X_W(k-1) X_k Rot(a_k, q_k),  z_k = R_W(k-1) R_k a_k,  o_k = the origin of X_W(k-1)
///   X_k, x_j(q) = X_W(b_j) r_j  (point j on body b_j, r_j its offset in that body), J_j = dx_j/dq,
///   column i = z_i x (x_j - o_i) for i < b_j (joints that move it), else 0.
/// Second derivatives (used by the C-space occupancy field; from dz_i/dq_k = z_k x z_i,
/// do_i/dq_k = z_k x (o_i - o_k) for k < i, and dx/dq_k = z_k x (x - o_k) for k < b):
///   d^2 x / dq_i dq_k = z_min(i,k) x J_max(i,k)   (J_m the Jacobian column, 0 for m >= b).
/// (For k < i the column's derivative (z_k x z_i) x (x - o_i) + z_i x (z_k x (x - o_i)) equals
/// z_k x J_i by the Jacobi identity: the column turns rigidly with joint k.)

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace foresight::imitation {

inline constexpr int kArmDof = 6;
using ArmVector = Eigen::Matrix<double, kArmDof, 1>;
using ArmMatrix = Eigen::Matrix<double, kArmDof, kArmDof>;
/// [3 x 6] d x / d q of a point (m/rad), in W.
using PointJacobian6 = Eigen::Matrix<double, 3, kArmDof>;

/// A ball rigidly attached to a link of the chain: the body points of thesis ch 8.
struct BodyPoint {
  std::string link;                                  ///< URDF link on the chain
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< centre in the link frame (m)
  double radius = 0;                                 ///< ball radius (m), >= 0
};

/// Results and buffers of Kinematics, sized by SerialChain::MakeData. One per caller.
struct ChainData {
  Eigen::Matrix3Xd p;                              ///< [3 x num_points] body points in W (m)
  std::vector<PointJacobian6> J;                   ///< [num_points] d p_j / d q
  Eigen::Vector3d p_ee = Eigen::Vector3d::Zero();  ///< end effector (tip link origin) in W
  PointJacobian6 J_ee = PointJacobian6::Zero();    ///< d p_ee / d q
  Eigen::Matrix<double, 3, kArmDof> z;             ///< unit joint axes z_k in W
  Eigen::Matrix<double, 3, kArmDof> o;             ///< joint origins o_k in W (on the axes)
  std::array<Eigen::Matrix3d, kArmDof + 1> R;      ///< body rotations in W (body 0: I)
  std::array<Eigen::Vector3d, kArmDof + 1> t;      ///< body origins in W (body 0: 0)
};

/// The immutable chain: load once, share, one ChainData per caller.
class SerialChain {
 public:
  /// An empty chain; use Load, FromText or LoadJaco.
  SerialChain() = default;

  /// Reads the path from `base_link` to `tip_link` of the URDF at `urdf_path` (urdfdom).
  /// Rules (a violation throws foresight::Error naming the file, the joint or the link):
  /// - both links exist and base_link is an ancestor of tip_link;
  /// - the joints on the path are fixed, revolute or continuous, with exactly kArmDof revolute or
  ///   continuous ones (the arm joints, in path order) with non-zero axes; joints off the path
  ///   (e.g. the JACO fingers) are ignored, i.e. held fixed;
  /// - limits: a revolute joint needs <limit> with finite lower < upper; a continuous joint takes
  ///   its <limit> lower/upper when the file gives finite lower < upper (j2n6s300: +-2 pi), and
  ///   -inf/+inf otherwise (urdfdom's default 0/0 of a missing <limit>);
  /// - every body point names a link on the path (base and tip included), has a finite offset and
  ///   a finite radius >= 0.
  static SerialChain Load(const std::string& urdf_path, const std::string& base_link,
                          const std::string& tip_link, std::vector<BodyPoint> points);
  /// Load from a URDF text; `source` names it in error messages.
  static SerialChain FromText(const std::string& urdf_text, const std::string& source,
                              const std::string& base_link, const std::string& tip_link,
                              std::vector<BodyPoint> points);
  /// jaco_dir/j2n6s300.urdf from link `root` (if the file has it, else the URDF root) to
  /// j2n6s300_end_effector, with JacoBodyPoints().
  static SerialChain LoadJaco(const std::string& jaco_dir);
  /// The default JACO body points: balls covering the collision cylinders of the moving links
  /// j2n6s300_link_1..6 (all of radius r = 0.025 m). A cylinder of length L about axis a through c
  /// gets n = clamp(ceil(L / (2 r)), 1, 3) balls at c + a L ((i + 1/2) / n - 1/2), i < n, of radius
  /// sqrt(r^2 + (L / 2n)^2): each covers its slice of the cylinder exactly, so the union covers
  /// the cylinder (link_1: 2, link_2: 3, link_3: 3, link_4..6: 1 each). The fixed base link is
  /// left out (no joint moves it, so it adds nothing to the C-space field), and one ball of radius
  /// 0.025 m at the end effector is added last (thesis: the end effector is a body point; the
  /// fingers, off the chain, are not modelled). 12 points.
  static std::vector<BodyPoint> JacoBodyPoints();

  const std::string& name() const { return name_; }  ///< <robot name>
  const std::string& base_link() const { return base_link_; }
  const std::string& tip_link() const { return tip_link_; }
  /// Links on the path from base to tip, in order.
  const std::vector<std::string>& chain_links() const { return chain_links_; }
  /// Arm joint names, base to tip (the order of ArmVector entries).
  const std::array<std::string, kArmDof>& joint_names() const { return joint_names_; }
  /// Whether arm joint k is continuous (else revolute).
  bool continuous(int joint) const { return continuous_[static_cast<size_t>(joint)]; }
  const ArmVector& lower() const { return lower_; }  ///< joint limits (rad); see Load
  const ArmVector& upper() const { return upper_; }

  int num_points() const { return static_cast<int>(points_.size()); }
  const std::vector<BodyPoint>& points() const { return points_; }
  /// Number of arm joints that move body point j: columns >= this of its Jacobian are zero.
  int point_body(int j) const { return point_body_[static_cast<size_t>(j)]; }

  /// Buffers for Kinematics (allocates; call once per caller).
  ChainData MakeData() const;

 private:
  friend void Kinematics(const SerialChain&, const ArmVector&, ChainData*);

  std::string name_, base_link_, tip_link_;
  std::vector<std::string> chain_links_;
  std::array<std::string, kArmDof> joint_names_;
  std::array<bool, kArmDof> continuous_{};
  ArmVector lower_ = ArmVector::Zero(), upper_ = ArmVector::Zero();
  // Joint k: its origin in body k (rotation, translation) and its unit axis in the joint frame.
  std::array<Eigen::Matrix3d, kArmDof> R_joint_;
  std::array<Eigen::Vector3d, kArmDof> t_joint_, axis_;
  // Tip: body and offset in that body.
  int tip_body_ = 0;
  Eigen::Vector3d tip_offset_ = Eigen::Vector3d::Zero();
  // Body points: public description; body index and offset in the body frame (hot path).
  std::vector<BodyPoint> points_;
  std::vector<int> point_body_;
  Eigen::Matrix3Xd point_offset_;
};

/// Body points, end effector, their Jacobians, joint axes and body poses at q. No allocation.
/// @param q [6] arm joint angles (rad); not checked against the limits.
/// @param data from chain.MakeData().
void Kinematics(const SerialChain& chain, const ArmVector& q, ChainData* data);

/// Adds the C-space gradient and Hessian of a potential phi(x_j(q)) of body point j, given
/// g = grad phi and H = Hess phi at x_j (from a previous Kinematics call at q):
///   grad += J_j' g,   hess += J_j' H J_j + M,   M_ik = g . (z_min(i,k) x J_max(i,k))
/// (the second-derivative term sum_k (dJ_j/dq_k)' g e_k', symmetric; see the file comment).
/// `hess` may be null (gradient only). No allocation.
void AddPointPotential(const ChainData& data, int point, const Eigen::Vector3d& g,
                       const Eigen::Matrix3d& H, ArmVector* grad, ArmMatrix* hess);

/// Damped least squares on the end-effector position from q_init:
///   dq = J' (J J' + lambda^2 I)^-1 (target - p_ee),  lambda = 1e-2 m, steps capped at 0.5 rad
/// (max norm), q clamped to the limits. True when ||p_ee(q) - target|| <= tolerance (m) within
/// max_iterations; *q holds the last iterate either way. No allocation besides `data`'s set-up.
bool InverseKinematics(const SerialChain& chain, const Eigen::Vector3d& target,
                       const ArmVector& q_init, ArmVector* q, double tolerance = 1e-6,
                       int max_iterations = 200);

}  // namespace foresight::imitation
