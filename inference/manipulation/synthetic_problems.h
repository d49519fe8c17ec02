#pragma once
/// Synthetic manipulation problems for the quickstart and for tests that must run without
/// ../shared/data: tables, shelves and loose boxes and cans around the Panda, like the
/// MotionBenchMaker families (table_pick, bookshelf_*), plus start/goal configurations drawn by a
/// caller-supplied validity predicate (the validity checker lives in validity.h).
///
/// Layout (frame W = panda_link0, z up; the robot faces +x). Every piece is placed at an azimuth
/// within +-max_azimuth_deg of +x:
/// - a table: a top board (tangential width x radial depth x 0.04 m) whose edge nearest the base
///   is at horizontal distance r in [reach_min, reach_max], at height table_height, facing the
///   base (its edges parallel/perpendicular to the line to the base), on four 0.05 m square legs
///   down to floor_z;
/// - a shelf: two side panels and 2..4 boards (0.03 m thick, 0.25..0.40 m apart, the lowest at
///   shelf_bottom), open towards the base, front at horizontal distance r in
///   [reach_min, reach_max], facing the base;
/// - a box: sides in [0.04, 0.20] m, uniformly random orientation, centre at a random azimuth,
///   height in [object_z_min, object_z_max] and horizontal distance in
///   [reach_min + half diagonal, max(reach_max, reach_min + half diagonal)];
/// - a cylinder ("can"): upright, radius in [0.02, 0.05] m, height in [0.08, 0.25] m, placed like a
///   box.
/// Tables and shelves get disjoint azimuth sectors (the +-max_azimuth range split evenly, in a
/// seeded order), which spreads them out; wide pieces close to the base may still touch, and
/// loose boxes and cans may intersect anything (the world allows overlapping obstacles).
/// Guarantees (tested): every obstacle point is at horizontal distance >= reach_min from the base
/// axis (the z axis of W) and at height >= floor_z. Deterministic in (config, seed) on every
/// platform (own SplitMix64 stream, no std:: distributions).

#include <cstdint>
#include <functional>
#include <string>

#include "core/config.h"
#include "inference/manipulation/joint_types.h"
#include "inference/manipulation/mbm_problem.h"
#include "inference/manipulation/world.h"

namespace foresight::manipulation {

struct SyntheticSceneConfig {
  int tables = 1;               ///< tables (top + 4 legs = 5 boxes each)
  int shelves = 1;              ///< shelves (2 sides + 2..4 boards each)
  int boxes = 3;                ///< loose boxes at random poses
  int cylinders = 2;            ///< loose upright cans
  double reach_min = 0.3;       ///< no obstacle comes closer to the base axis (m)
  double reach_max = 0.8;       ///< tables/shelves start, loose objects are centred, within (m)
  double max_azimuth_deg = 60;  ///< pieces are placed within +- this of +x (deg)
  double floor_z = -0.4;        ///< table legs stand on this height (m)
  double table_height_min = -0.1, table_height_max = 0.2;  ///< table top surface z (m)
  double shelf_bottom_min = -0.2, shelf_bottom_max = 0.2;  ///< lowest shelf board z (m)
  double object_z_min = 0.0, object_z_max = 0.8;           ///< loose object centre z (m)

  template <class A>
  void Serialize(A* a) {
    a->Visit("tables", &tables, config::Range::Closed(0, 4), "tables (top + 4 legs)");
    a->Visit("shelves", &shelves, config::Range::Closed(0, 4), "shelves (sides + 2..4 boards)");
    a->Visit("boxes", &boxes, config::Range::Closed(0, 100), "loose boxes at random poses");
    a->Visit("cylinders", &cylinders, config::Range::Closed(0, 100), "loose upright cans");
    a->Visit("reach_min", &reach_min, config::Range::Positive(),
             "least horizontal distance of any obstacle from the base axis (m)");
    a->Visit("reach_max", &reach_max, config::Range::Positive(),
             "tables and shelves start, loose objects are centred, within this distance (m)");
    a->Visit("max_azimuth_deg", &max_azimuth_deg, config::Range::Closed(0, 90),
             "pieces are placed within +- this angle of +x (deg)");
    a->Visit("floor_z", &floor_z, config::Range::Any(), "height the table legs stand on (m)");
    a->Visit("table_height_min", &table_height_min, config::Range::Any(),
             "lowest table top surface (m)");
    a->Visit("table_height_max", &table_height_max, config::Range::Any(),
             "highest table top surface (m)");
    a->Visit("shelf_bottom_min", &shelf_bottom_min, config::Range::Any(),
             "lowest bottom shelf board (m)");
    a->Visit("shelf_bottom_max", &shelf_bottom_max, config::Range::Any(),
             "highest bottom shelf board (m)");
    a->Visit("object_z_min", &object_z_min, config::Range::Any(), "lowest loose object centre (m)");
    a->Visit("object_z_max", &object_z_max, config::Range::Any(),
             "highest loose object centre (m)");
  }
  /// Rules across fields (reach_min < reach_max, min <= max, floor below tables and shelves).
  /// Throws Error naming `where`.
  void Validate(const std::string& where) const;
};

/// How start and goal are drawn.
struct StartGoalConfig {
  int max_attempts = 10000;     ///< draws for the start, and again for the goal
  double min_separation = 1.0;  ///< least |goal - start|_2 (rad)

  template <class A>
  void Serialize(A* a) {
    a->Visit("max_attempts", &max_attempts, config::Range::Closed(1, 100000000),
             "uniform draws tried for the start, and again for the goal");
    a->Visit("min_separation", &min_separation, config::Range::NonNegative(),
             "least C-space distance |goal - start|_2 (rad)");
  }
};

/// A world of config.tables tables, config.shelves shelves, then the loose boxes and cans
/// (obstacle ids table0_top, table0_leg0.., shelf0_side_left, shelf0_board0.., box0.., can0..).
/// Throws Error for an invalid config.
World MakeSyntheticWorld(const SyntheticSceneConfig& config, std::uint64_t seed);

struct StartGoal {
  JointVector start = JointVector::Zero(), goal = JointVector::Zero();  ///< rad
  int start_draws = 0, goal_draws = 0;                                  ///< uniform draws used
};

/// Draws a start uniformly in [lower, upper] until `is_valid` accepts one, then a goal likewise
/// that is also at least min_separation from the start (the predicate is not called for goals
/// that are too close). Throws Error naming the limits, the attempts and the seed when
/// max_attempts draws find none, and for limits that are not finite with lower < upper.
/// @param lower, upper [7] joint limits (rad)
StartGoal SampleStartGoal(const JointVector& lower, const JointVector& upper,
                          const std::function<bool(const JointVector&)>& is_valid,
                          const StartGoalConfig& config, std::uint64_t seed);

/// MakeSyntheticWorld(scene, seed), then SampleStartGoal with `is_valid` bound to that world
/// (the reference is valid during the call only), all from one seed. family = "synthetic",
/// index = 0, source = "synthetic (seed N)".
ManipulationProblem MakeSyntheticProblem(
    const SyntheticSceneConfig& scene, const StartGoalConfig& sampling, const JointVector& lower,
    const JointVector& upper,
    const std::function<bool(const World& world, const JointVector& q)>& is_valid,
    std::uint64_t seed);

}  // namespace foresight::manipulation
