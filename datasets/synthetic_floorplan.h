#pragma once
/// A synthetic indoor environment explored by several robots with planar lasers: the substitute
/// for the thesis's "simulated dataset of two robots in an indoor environment" (chapter 3, Fast-BHM
/// map fusion), whose scans were not published.
///
/// The floor plan is a rectangle divided into a grid of rooms. Interior walls between neighbouring
/// rooms have doors on a seeded spanning tree of the room grid (so every room is reachable), at
/// seeded positions along the wall; each room may hold a few seeded square boxes placed clear of
/// the robots' paths. Walls are line segments (ray-cast as such). Robot k starts in its own room
/// (robot 0 in the first room, the last robot in the last room) and walks a seeded tour: room
/// centre -> in front of a door -> through the door, perpendicular to the wall -> next room's
/// centre, preferring the rooms it has visited least, at constant speed, scanning every
/// scan_period. Everything is deterministic in (config, seed).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/config.h"
#include "datasets/laser_scan.h"

namespace foresight {

struct SyntheticFloorplanConfig {
  double width = 20.0;      ///< extent of the floor plan along x (m); it spans [0, width]
  double height = 15.0;     ///< extent along y (m); it spans [0, height]
  int rooms_x = 3;          ///< room grid columns
  int rooms_y = 2;          ///< room grid rows
  double door_width = 1.0;  ///< m
  /// Least distance of boxes from the robots' paths and of doors from room corners (m).
  double clearance = 0.4;
  int boxes_per_room = 1;  ///< seeded square obstacles per room (fewer when they do not fit)
  double box_size = 0.8;   ///< side of a box (m)
  int num_robots = 2;
  int scans_per_robot = 150;
  double speed = 0.5;         ///< m/s
  double scan_period = 0.2;   ///< s between scans of one robot
  int beams = 180;            ///< beams per scan, spread like CARMEN: -fov/2 + i * fov / beams
  double fov = M_PI;          ///< field of view (rad)
  double max_range = 20.0;    ///< m; beams hitting nothing within it read exactly max_range
  double range_noise = 0.01;  ///< std of the Gaussian range noise (m)

  template <class A>
  void Serialize(A* a) {
    a->Visit("width", &width, config::Range::Positive(), "extent of the floor plan along x (m)");
    a->Visit("height", &height, config::Range::Positive(), "extent of the floor plan along y (m)");
    a->Visit("rooms_x", &rooms_x, config::Range::Closed(1, 100), "room grid columns");
    a->Visit("rooms_y", &rooms_y, config::Range::Closed(1, 100),
             "room grid rows (rooms_x * rooms_y >= 2)");
    a->Visit("door_width", &door_width, config::Range::Positive(), "width of a door (m)");
    a->Visit("clearance", &clearance, config::Range::NonNegative(),
             "least distance of boxes from robot paths and of doors from room corners (m)");
    a->Visit("boxes_per_room", &boxes_per_room, config::Range::Closed(0, 10),
             "seeded square obstacles per room (fewer when they do not fit)");
    a->Visit("box_size", &box_size, config::Range::Positive(), "side of a box obstacle (m)");
    a->Visit("num_robots", &num_robots, config::Range::Closed(1, 8), "number of robots");
    a->Visit("scans_per_robot", &scans_per_robot, config::Range::AtLeast(1),
             "laser scans recorded by each robot");
    a->Visit("speed", &speed, config::Range::NonNegative(), "robot speed (m/s)");
    a->Visit("scan_period", &scan_period, config::Range::Positive(),
             "time between two scans of one robot (s)");
    a->Visit("beams", &beams, config::Range::AtLeast(1), "beams per scan");
    a->Visit("fov", &fov, config::Range::OpenClosed(0, 2 * M_PI), "laser field of view (rad)");
    a->Visit("max_range", &max_range, config::Range::Positive(),
             "laser range (m); no return reads exactly max_range, so sample points with "
             "occupancy max_range <= this");
    a->Visit("range_noise", &range_noise, config::Range::NonNegative(),
             "std of the Gaussian range noise (m)");
  }
};

/// Walls (line segments) of a floor plan, plus the room graph the robots walk on.
struct FloorPlan {
  struct Door {
    int room_a = 0, room_b = 0;                        ///< the two rooms it connects
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< middle of the opening (m)
    /// Unit normal of the wall, pointing from room_a to room_b.
    Eigen::Vector2d normal = Eigen::Vector2d::Zero();
    /// Robots cross on the normal line, from centre - approach * normal to centre + approach *
    /// normal (m).
    double approach = 0;
  };
  std::vector<Eigen::Vector4d> walls;         ///< segments (x0, y0, x1, y1) in W (m)
  double width = 0, height = 0;               ///< the plan spans [0, width] x [0, height] (m)
  std::vector<Eigen::Vector2d> room_centres;  ///< room r = iy * rooms_x + ix
  std::vector<Door> doors;

  /// True when p_WP is within `wall_half_thickness` (m) of a wall segment.
  bool Occupied(const Eigen::Vector2d& p_WP, double wall_half_thickness) const;
  /// Distance (m) along the ray from p_WO at world angle `angle` (rad) to the first wall, or +inf
  /// when no wall is within max_range.
  double Raycast(const Eigen::Vector2d& p_WO, double angle, double max_range) const;
};

/// Outer walls, interior walls on the room grid with doors on a seeded spanning tree of the rooms,
/// and seeded boxes. Errors: rooms too small for a door (or for the robots' door approach), fewer
/// than 2 rooms.
FloorPlan GenerateFloorPlan(const SyntheticFloorplanConfig& config, std::uint64_t seed);

/// Scans of config.num_robots robots touring `plan` (see the file comment), ordered by time;
/// robot k's j-th scan is at time (j + k / num_robots) * scan_period. Ranges are ray-cast distances
/// plus Gaussian noise (at least 1 mm); beams hitting nothing read max_range.
std::vector<LaserScan> SimulateRobots(const FloorPlan& plan, const SyntheticFloorplanConfig& config,
                                      std::uint64_t seed);

}  // namespace foresight
