#pragma once
/// Basis point set (BPS) encoding of a manipulation world (thesis ch 9, learned GFCS sampler;
/// Prokudin et al., "Efficient Learning on Point Clouds with Basis Point Sets", ICCV 2019): the
/// environment is a fixed lattice of reference points in W, each holding its distance to the
/// nearest obstacle surface point, clipped at max_distance.
///
/// The distances are exact: for each reference point p the value is min_i |sd_i(p)| over the
/// primitives i (sd_i the exact signed distance of world.h), i.e. the distance to the nearest
/// point of any primitive's surface. A point inside an obstacle gets its distance to that
/// obstacle's surface, as a dense surface point cloud (World::SurfacePoints) would give; surfaces
/// of overlapping primitives count even where they lie inside another primitive (the point cloud
/// keeps them too). An empty world gives max_distance everywhere.
///
///   BpsLattice lattice;                 // lower, upper, spacing, max_distance (config struct)
///   lattice.Validate("config.yaml");
///   CheckLatticeCovers(lattice, ReachBox(robot), "config.yaml");
///   Eigen::VectorXf d = EncodeBps(world, lattice);   // [lattice.size()] (m)

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "core/config.h"
#include "inference/manipulation/robot_model.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

/// A point (m) as a config mapping {x, y, z}, for config structs holding an Eigen::Vector3d.
struct ConfigPoint3 {
  double x = 0, y = 0, z = 0;

  template <class A>
  void Serialize(A* a) {
    a->Visit("x", &x, config::Range::Any(), "x (m)");
    a->Visit("y", &y, config::Range::Any(), "y (m)");
    a->Visit("z", &z, config::Range::Any(), "z (m)");
  }
};

/// The reference points: lower + spacing * (i, j, k) for every such point within upper (inclusive
/// up to 1e-9 m), i fastest, then j, then k (x fastest, then y, then z).
struct BpsLattice {
  /// Defaults: a cube of 17 x 17 x 17 points (N_R = 4913) at 0.15 m covering the ReachBox of
  /// the VAMP Panda ([-1.113, -1.113, -0.780] .. [1.113, 1.113, 1.446] m) and of the built-in one
  /// (z up to 1.456 m); also at 0.3, 0.6 and 1.2 m spacing.
  Eigen::Vector3d lower = Eigen::Vector3d(-1.2, -1.2, -0.9);  ///< first point (m, frame W)
  Eigen::Vector3d upper = Eigen::Vector3d(1.2, 1.2, 1.5);     ///< last point at most (m)
  double spacing = 0.15;                                      ///< lattice step (m)
  double max_distance = 1.0;                                  ///< distances are clipped here (m)

  template <class A>
  void Serialize(A* a) {
    ConfigPoint3 lo{lower.x(), lower.y(), lower.z()}, hi{upper.x(), upper.y(), upper.z()};
    a->Visit("lower", &lo, config::Range::Any(), "first lattice point in W (m)");
    a->Visit("upper", &hi, config::Range::Any(), "the lattice ends at or before this point (m)");
    lower = Eigen::Vector3d(lo.x, lo.y, lo.z);
    upper = Eigen::Vector3d(hi.x, hi.y, hi.z);
    a->Visit("spacing", &spacing, config::Range::Positive(), "lattice step (m)");
    a->Visit("max_distance", &max_distance, config::Range::Positive(),
             "surface distances are clipped at this value (m)");
  }
  /// lower <= upper on every axis, spacing and max_distance finite and positive, at most 10^6
  /// points. Throws Error naming `where`, the field and the values.
  void Validate(const std::string& where) const;

  /// Points along each axis.
  Eigen::Vector3i counts() const;
  /// N_R = product of counts().
  int size() const;
  /// [3 x size()] the reference points (m), x fastest.
  Eigen::Matrix3Xd points() const;
};

/// [lattice.size()] min(max_distance, distance from each reference point to the nearest obstacle
/// surface) (m), float as the encoder takes it.
Eigen::VectorXf EncodeBps(const World& world, const BpsLattice& lattice);

/// Throws Error naming `where`, the axis and the values when the lattice's points do not span
/// `workspace` on some axis (first point > box min or last point < box max, 1e-9 m slack).
void CheckLatticeCovers(const BpsLattice& lattice, const Eigen::AlignedBox3d& workspace,
                        const std::string& where);

/// A conservative box around everything the robot can reach, in W: each collision sphere, on body
/// b, stays within |o_2 - o_1| + ... + |o_b - o_{b-1}| + |c - o_b| + radius of the first arm
/// joint's origin o_1 (o_k the origin of arm joint k on its axis, c the sphere centre; every term
/// is a distance between two points of one rigid body, hence the same at every configuration,
/// and is measured at q = 0); spheres fixed to the base are added as they are. The box is o_1 +-
/// the largest such reach, joined with the base spheres' boxes. Joint limits are ignored (it is an
/// upper bound). Throws Error for a model without arm joints or spheres.
Eigen::AlignedBox3d ReachBox(const RobotModel& robot);

}  // namespace foresight::manipulation
