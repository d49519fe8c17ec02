#include "inference/manipulation/synthetic_problems.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <vector>

#include "core/error.h"

namespace foresight::manipulation {
namespace {

constexpr double kBoardThickness = 0.03;  // shelf boards and sides (m)
constexpr double kTableTopThickness = 0.04;
constexpr double kLegSide = 0.05;
constexpr double kMinLegLength = 0.05;

/// SplitMix64 (Steele et al. 2014): portable, so a seed gives the same scene everywhere.
class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t stream) : state_(seed ^ (stream * 0xD1B54A32D192ED03ull)) {
    Next();
  }
  std::uint64_t Next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Uniform integer in [lo, hi].
  int UniformInt(int lo, int hi) {
    return lo + static_cast<int>(Next() % static_cast<std::uint64_t>(hi - lo + 1));
  }

 private:
  std::uint64_t state_;
};

/// Uniformly random rotation (Shoemake 1992).
Eigen::Matrix3d RandomRotation(Rng* rng) {
  const double u1 = rng->Uniform(), u2 = rng->Uniform(), u3 = rng->Uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const Eigen::Quaterniond q(b * std::cos(2 * M_PI * u3), a * std::sin(2 * M_PI * u2),
                             a * std::cos(2 * M_PI * u2), b * std::sin(2 * M_PI * u3));
  return q.normalized().toRotationMatrix();
}

/// A frame at horizontal distance `r` and azimuth `phi` from the base axis, height z, with local
/// x pointing away from the base (radial) and y tangential.
Eigen::Isometry3d FacingFrame(double r, double phi, double z) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
  return X;
}

/// A box of full sizes `size` centred at p_F in frame X_WF.
Box BoxIn(const Eigen::Isometry3d& X_WF, const Eigen::Vector3d& p_F, const Eigen::Vector3d& size) {
  Eigen::Isometry3d X_FB = Eigen::Isometry3d::Identity();
  X_FB.translation() = p_F;
  return Box{X_WF * X_FB, 0.5 * size};
}

void AddTable(const SyntheticSceneConfig& c, int k, double phi, Rng* rng, World* world) {
  const double r = rng->Uniform(c.reach_min, c.reach_max);
  const double width = rng->Uniform(0.6, 1.2), depth = rng->Uniform(0.4, 0.8);
  const double top = rng->Uniform(c.table_height_min, c.table_height_max);
  // Frame F: origin on the base-facing edge's midpoint at floor height, x radial, y tangential.
  const Eigen::Isometry3d X_WF = FacingFrame(r, phi, 0.0);
  const std::string name = "table" + std::to_string(k);
  world->AddBox(name + "_top", BoxIn(X_WF, {0.5 * depth, 0.0, top - 0.5 * kTableTopThickness},
                                     {depth, width, kTableTopThickness}));
  const double leg_top = top - kTableTopThickness;
  const double leg_length = leg_top - c.floor_z;
  int leg = 0;
  for (const double x : {0.5 * kLegSide + 0.02, depth - 0.5 * kLegSide - 0.02}) {
    for (const double y :
         {-0.5 * width + 0.5 * kLegSide + 0.02, 0.5 * width - 0.5 * kLegSide - 0.02}) {
      world->AddBox(
          name + "_leg" + std::to_string(leg++),
          BoxIn(X_WF, {x, y, c.floor_z + 0.5 * leg_length}, {kLegSide, kLegSide, leg_length}));
    }
  }
}

void AddShelf(const SyntheticSceneConfig& c, int k, double phi, Rng* rng, World* world) {
  const double r = rng->Uniform(c.reach_min, c.reach_max);
  const double width = rng->Uniform(0.6, 1.0), depth = rng->Uniform(0.3, 0.45);
  const double bottom = rng->Uniform(c.shelf_bottom_min, c.shelf_bottom_max);
  const int boards = rng->UniformInt(2, 4);
  const double gap = rng->Uniform(0.25, 0.40);
  const Eigen::Isometry3d X_WF = FacingFrame(r, phi, 0.0);
  const std::string name = "shelf" + std::to_string(k);
  for (int b = 0; b < boards; ++b) {
    world->AddBox(
        name + "_board" + std::to_string(b),
        BoxIn(X_WF, {0.5 * depth, 0.0, bottom + b * gap}, {depth, width, kBoardThickness}));
  }
  const double z_lo = bottom - 0.5 * kBoardThickness;
  const double z_hi = bottom + (boards - 1) * gap + 0.5 * kBoardThickness;
  for (const double side : {1.0, -1.0}) {
    world->AddBox(
        name + (side > 0 ? "_side_left" : "_side_right"),
        BoxIn(X_WF, {0.5 * depth, side * 0.5 * (width + kBoardThickness), 0.5 * (z_lo + z_hi)},
              {depth, kBoardThickness, z_hi - z_lo}));
  }
}

/// Horizontal distance and height of a loose object's centre, given its bounding radius.
Eigen::Vector3d LooseCentre(const SyntheticSceneConfig& c, double bounding_radius, Rng* rng) {
  const double a = c.max_azimuth_deg * M_PI / 180.0;
  const double phi = rng->Uniform(-a, a);
  const double r_lo = c.reach_min + bounding_radius;
  const double r = rng->Uniform(r_lo, std::max(r_lo, c.reach_max));
  const double z =
      std::max(rng->Uniform(c.object_z_min, c.object_z_max), c.floor_z + bounding_radius);
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

std::string Limits(const JointVector& lower, const JointVector& upper) {
  std::ostringstream os;
  os << "[";
  for (int j = 0; j < kDof; ++j) os << (j ? ", " : "") << lower(j) << ".." << upper(j);
  os << "]";
  return os.str();
}

JointVector Draw(const JointVector& lower, const JointVector& upper, Rng* rng) {
  JointVector q;
  for (int j = 0; j < kDof; ++j) q(j) = rng->Uniform(lower(j), upper(j));
  return q;
}

}  // namespace

void SyntheticSceneConfig::Validate(const std::string& where) const {
  FS_THROW_UNLESS(reach_min < reach_max, where, ": reach_min ", reach_min,
                  " must be below reach_max ", reach_max);
  FS_THROW_UNLESS(table_height_min <= table_height_max, where, ": table_height_min ",
                  table_height_min, " > table_height_max ", table_height_max);
  FS_THROW_UNLESS(shelf_bottom_min <= shelf_bottom_max, where, ": shelf_bottom_min ",
                  shelf_bottom_min, " > shelf_bottom_max ", shelf_bottom_max);
  FS_THROW_UNLESS(object_z_min <= object_z_max, where, ": object_z_min ", object_z_min,
                  " > object_z_max ", object_z_max);
  FS_THROW_UNLESS(tables == 0 || table_height_min - kTableTopThickness - floor_z >= kMinLegLength,
                  where, ": table_height_min ", table_height_min, " leaves legs shorter than ",
                  kMinLegLength, " m above floor_z ", floor_z);
  FS_THROW_UNLESS(shelves == 0 || shelf_bottom_min - 0.5 * kBoardThickness >= floor_z, where,
                  ": shelf_bottom_min ", shelf_bottom_min, " puts the lowest board below floor_z ",
                  floor_z);
}

World MakeSyntheticWorld(const SyntheticSceneConfig& config, std::uint64_t seed) {
  config.Validate("synthetic scene config");
  Rng rng(seed, 1);
  World world;
  // Tables and shelves in disjoint azimuth sectors, in a seeded order.
  const int pieces = config.tables + config.shelves;
  std::vector<int> sector(static_cast<std::size_t>(pieces));
  std::iota(sector.begin(), sector.end(), 0);
  for (int i = pieces - 1; i > 0; --i)
    std::swap(sector[static_cast<std::size_t>(i)],
              sector[static_cast<std::size_t>(rng.UniformInt(0, i))]);
  const double a = config.max_azimuth_deg * M_PI / 180.0;
  const double width = pieces > 0 ? 2.0 * a / pieces : 0.0;
  auto azimuth = [&](int piece) {
    const double lo = -a + sector[static_cast<std::size_t>(piece)] * width;
    return rng.Uniform(lo + 0.25 * width, lo + 0.75 * width);
  };
  for (int k = 0; k < config.tables; ++k) AddTable(config, k, azimuth(k), &rng, &world);
  for (int k = 0; k < config.shelves; ++k)
    AddShelf(config, k, azimuth(config.tables + k), &rng, &world);
  for (int k = 0; k < config.boxes; ++k) {
    const Eigen::Vector3d size(rng.Uniform(0.04, 0.20), rng.Uniform(0.04, 0.20),
                               rng.Uniform(0.04, 0.20));
    Box box;
    box.half_size = 0.5 * size;
    box.X_WB.linear() = RandomRotation(&rng);
    box.X_WB.translation() = LooseCentre(config, box.half_size.norm(), &rng);
    world.AddBox("box" + std::to_string(k), box);
  }
  for (int k = 0; k < config.cylinders; ++k) {
    Cylinder can;
    can.radius = rng.Uniform(0.02, 0.05);
    can.half_height = 0.5 * rng.Uniform(0.08, 0.25);
    // Upright: the horizontal extent is the radius; the vertical one the half height.
    const Eigen::Vector3d c = LooseCentre(config, can.radius, &rng);
    can.X_WC.translation() =
        Eigen::Vector3d(c.x(), c.y(), std::max(c.z(), config.floor_z + can.half_height));
    world.AddCylinder("can" + std::to_string(k), can);
  }
  return world;
}

StartGoal SampleStartGoal(const JointVector& lower, const JointVector& upper,
                          const std::function<bool(const JointVector&)>& is_valid,
                          const StartGoalConfig& config, std::uint64_t seed) {
  FS_THROW_UNLESS(lower.allFinite() && upper.allFinite() && (lower.array() < upper.array()).all(),
                  "start/goal sampling: joint limits ", Limits(lower, upper),
                  " must be finite with lower < upper");
  FS_THROW_UNLESS(config.max_attempts >= 1, "start/goal sampling: max_attempts ",
                  config.max_attempts, " must be at least 1");
  FS_THROW_UNLESS(static_cast<bool>(is_valid), "start/goal sampling: no validity predicate given");
  Rng rng(seed, 2);
  StartGoal out;
  bool found = false;
  while (!found && out.start_draws < config.max_attempts) {
    ++out.start_draws;
    out.start = Draw(lower, upper, &rng);
    found = is_valid(out.start);
  }
  FS_THROW_UNLESS(found, "start/goal sampling: no valid start in ", out.start_draws,
                  " uniform draws within joint limits ", Limits(lower, upper), " (seed ", seed,
                  "): the validity predicate rejected every one");
  found = false;
  int too_close = 0;
  while (!found && out.goal_draws < config.max_attempts) {
    ++out.goal_draws;
    out.goal = Draw(lower, upper, &rng);
    if ((out.goal - out.start).norm() < config.min_separation) {
      ++too_close;
      continue;
    }
    found = is_valid(out.goal);
  }
  FS_THROW_UNLESS(found, "start/goal sampling: no valid goal in ", out.goal_draws,
                  " uniform draws within joint limits ", Limits(lower, upper), " (seed ", seed,
                  "): ", too_close, " were closer than min_separation ", config.min_separation,
                  " rad to the start, the predicate rejected the rest");
  return out;
}

ManipulationProblem MakeSyntheticProblem(
    const SyntheticSceneConfig& scene, const StartGoalConfig& sampling, const JointVector& lower,
    const JointVector& upper,
    const std::function<bool(const World& world, const JointVector& q)>& is_valid,
    std::uint64_t seed) {
  FS_THROW_UNLESS(static_cast<bool>(is_valid), "synthetic problem: no validity predicate given");
  ManipulationProblem p;
  p.family = "synthetic";
  p.world = MakeSyntheticWorld(scene, seed);
  const World& world = p.world;
  const StartGoal sg = SampleStartGoal(
      lower, upper, [&](const JointVector& q) { return is_valid(world, q); }, sampling, seed);
  p.start = sg.start;
  p.goal = sg.goal;
  p.source = "synthetic (seed " + std::to_string(seed) + ")";
  return p;
}

}  // namespace foresight::manipulation
