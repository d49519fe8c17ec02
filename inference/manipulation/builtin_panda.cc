#include "inference/manipulation/builtin_panda.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <sstream>
#include <vector>

namespace foresight::manipulation {
namespace {

/// Franka's modified DH parameters (Craig): the frame of joint i is
/// RotX(alpha) TransX(a) TransZ(d) RotZ(q_i) relative to the frame of joint i-1.
struct DhRow {
  double a, d, alpha;
};
constexpr std::array<DhRow, kDof> kDh = {{{0, 0.333, 0},
                                          {0, 0, -M_PI / 2},
                                          {0, 0.316, M_PI / 2},
                                          {0.0825, 0, M_PI / 2},
                                          {-0.0825, 0.384, -M_PI / 2},
                                          {0, 0, M_PI / 2},
                                          {0.088, 0, M_PI / 2}}};
constexpr double kFlange = 0.107;  // link8 along z of link7
constexpr double kHandYaw = -M_PI / 4;
constexpr double kGraspOffset = 0.105;  // grasp target along z of the hand

// Franka datasheet limits (rad, rad/s).
constexpr std::array<double, kDof> kLower = {-2.8973, -1.7628, -2.8973, -3.0718,
                                             -2.8973, -0.0175, -2.8973};
constexpr std::array<double, kDof> kUpper = {2.8973, 1.7628, 2.8973, -0.0698,
                                             2.8973, 3.7525, 2.8973};
constexpr std::array<double, kDof> kVelocity = {2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61};

/// URDF origin of a DH row: translation RotX(alpha) (a, 0, d) ... = (a, -d sin alpha, d cos alpha)
/// and roll alpha (RotX(alpha) TransX(a) TransZ(d) = Trans(a, -d sin, d cos) RotX(alpha)).
Eigen::Vector3d DhTranslation(const DhRow& r) {
  return {r.a, -r.d * std::sin(r.alpha), r.d * std::cos(r.alpha)};
}

Eigen::Isometry3d DhTransform(const DhRow& r) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = DhTranslation(r);
  X.linear() = Eigen::AngleAxisd(r.alpha, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return X;
}

std::string LinkName(int k) {
  return k <= 8 ? "panda_link" + std::to_string(k) : (k == 9 ? "panda_hand" : "panda_grasptarget");
}

/// Spheres of radius r from a to b (inclusive), at most r apart, appended as CSV rows of `link`.
void SegmentSpheres(const std::string& link, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                    double r, std::ostringstream* csv) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / r)));
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(i) / n);
    *csv << link << "," << p.x() << "," << p.y() << "," << p.z() << "," << r << "\n";
  }
}

}  // namespace

BuiltinPandaDescription BuiltinPandaTexts() {
  BuiltinPandaDescription out;
  std::ostringstream urdf;
  urdf.precision(10);
  urdf << "<?xml version=\"1.0\"?>\n<robot name=\"panda_builtin\">\n";
  for (int k = 0; k <= 10; ++k) urdf << "  <link name=\"" << LinkName(k) << "\"/>\n";
  for (int j = 0; j < kDof; ++j) {
    const Eigen::Vector3d t = DhTranslation(kDh[j]);
    urdf << "  <joint name=\"panda_joint" << j + 1 << "\" type=\"revolute\">\n"
         << "    <parent link=\"" << LinkName(j) << "\"/><child link=\"" << LinkName(j + 1)
         << "\"/>\n"
         << "    <origin xyz=\"" << t.x() << " " << t.y() << " " << t.z() << "\" rpy=\""
         << kDh[j].alpha << " 0 0\"/>\n"
         << "    <axis xyz=\"0 0 1\"/>\n"
         << "    <limit lower=\"" << kLower[j] << "\" upper=\"" << kUpper[j]
         << "\" effort=\"87\" velocity=\"" << kVelocity[j] << "\"/>\n  </joint>\n";
  }
  urdf << "  <joint name=\"panda_joint8\" type=\"fixed\"><parent link=\"panda_link7\"/>"
       << "<child link=\"panda_link8\"/><origin xyz=\"0 0 " << kFlange << "\" rpy=\"0 0 0\"/>"
       << "</joint>\n"
       << "  <joint name=\"panda_hand_joint\" type=\"fixed\"><parent link=\"panda_link8\"/>"
       << "<child link=\"panda_hand\"/><origin xyz=\"0 0 0\" rpy=\"0 0 " << kHandYaw << "\"/>"
       << "</joint>\n"
       << "  <joint name=\"panda_grasptarget_hand\" type=\"fixed\"><parent link=\"panda_hand\"/>"
       << "<child link=\"panda_grasptarget\"/><origin xyz=\"0 0 " << kGraspOffset
       << "\" rpy=\"0 0 0\"/></joint>\n</robot>\n";
  out.urdf = urdf.str();

  // Joint frames at q = 0 in the base frame: X[k] is the frame of link k (k = 1..7).
  std::array<Eigen::Isometry3d, kDof + 1> X;
  X[0] = Eigen::Isometry3d::Identity();
  for (int j = 0; j < kDof; ++j) X[j + 1] = X[j] * DhTransform(kDh[j]);
  auto in_link = [&](int k, const Eigen::Vector3d& p_W) {
    return Eigen::Vector3d(X[k].inverse() * p_W);
  };
  auto origin = [&](int k) { return Eigen::Vector3d(X[k].translation()); };
  const Eigen::Vector3d flange = X[7] * Eigen::Vector3d(0, 0, kFlange);

  std::ostringstream csv;
  csv.precision(10);
  csv << "link,x,y,z,radius\n";
  const double arm = 0.07, wrist = 0.06, hand = 0.05;
  SegmentSpheres(LinkName(0), {0, 0, 0.05}, {0, 0, 0.15}, 0.08, &csv);
  SegmentSpheres(LinkName(1), in_link(1, {0, 0, 0.16}), in_link(1, origin(1)), arm, &csv);
  const Eigen::Vector3d mid23 = 0.5 * (origin(2) + origin(3));
  SegmentSpheres(LinkName(2), in_link(2, origin(2)), in_link(2, mid23), arm, &csv);
  SegmentSpheres(LinkName(3), in_link(3, mid23), in_link(3, origin(4)), arm, &csv);
  const Eigen::Vector3d elbow = origin(4) + (origin(5) - origin(4)) / 3.0;
  SegmentSpheres(LinkName(4), in_link(4, origin(4)), in_link(4, elbow), arm, &csv);
  SegmentSpheres(LinkName(5), in_link(5, elbow), in_link(5, origin(5)), arm, &csv);
  SegmentSpheres(LinkName(6), in_link(6, origin(6)), in_link(6, origin(7)), wrist, &csv);
  SegmentSpheres(LinkName(7), in_link(7, origin(7)), in_link(7, flange), wrist, &csv);
  // Hand: along its axis and across it (the fingers' span), in the hand frame.
  SegmentSpheres(LinkName(9), {0, 0, 0.02}, {0, 0, 0.08}, hand, &csv);
  SegmentSpheres(LinkName(9), {0, -0.08, 0.06}, {0, 0.08, 0.06}, 0.035, &csv);
  out.spheres_csv = csv.str();

  std::ostringstream srdf;
  srdf << "<?xml version=\"1.0\"?>\n<robot name=\"panda_builtin\">\n";
  for (int a = 0; a <= 9; ++a)
    for (int b = a + 1; b <= 9; ++b)
      if (b - a <= 3)
        srdf << "  <disable_collisions link1=\"" << LinkName(a) << "\" link2=\"" << LinkName(b)
             << "\" reason=\"Adjacent\"/>\n";
  srdf << "</robot>\n";
  out.srdf = srdf.str();
  return out;
}

RobotModel BuiltinPanda() {
  const BuiltinPandaDescription d = BuiltinPandaTexts();
  return RobotModel::FromText(d.urdf, d.spheres_csv, d.srdf, "<built-in Panda>");
}

}  // namespace foresight::manipulation
