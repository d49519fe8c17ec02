#include "datasets/crowd_sim.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/parse.h"

namespace foresight {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Vector2d Perp(const Eigen::Vector2d& u) { return {-u.y(), u.x()}; }

/// -dE/dtau / E = m/tau + 1/tau0 at the clamped tau, times E: the force magnitude factor.
double ForceFactor(double tau, double k, const PowerLawParams& p) {
  const double t = std::max(tau, p.tau_min);
  return PowerLawEnergy(t, k, p.exponent, p.tau0) * (p.exponent / t + 1.0 / p.tau0);
}

Eigen::Vector2d CapNorm(const Eigen::Vector2d& v, double cap) {
  const double n = v.norm();
  return n > cap ? Eigen::Vector2d(v * (cap / n)) : v;
}

/// The segment body of a thick wall as seen from x: unit normal towards x, distance along it.
struct BodyContact {
  bool valid = false;
  Eigen::Vector2d n = Eigen::Vector2d::Zero();
  double s = 0;
};

BodyContact Body(const Eigen::Vector2d& x, const SimWall& w) {
  BodyContact b;
  const Eigen::Vector2d d = w.q - w.p;
  const double len = d.norm();
  if (len < 1e-12) return b;
  b.n = Perp(d / len);
  b.s = (x - w.p).dot(b.n);
  if (b.s < 0) {
    b.n = -b.n;
    b.s = -b.s;
  }
  b.valid = true;
  return b;
}

/// Time to collision with the body of the segment (not its end caps), or inf.
double BodyTimeToCollision(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r,
                           const SimWall& w, BodyContact* contact) {
  const BodyContact b = Body(x, w);
  if (!b.valid) return kInf;
  const double approach = -v.dot(b.n);
  if (approach <= 0) return kInf;
  const double radius = r + w.half_thickness;
  const double t = std::max(0.0, (b.s - radius) / approach);
  const Eigen::Vector2d d = w.q - w.p;
  const double along = (x + v * t - w.p).dot(d) / d.squaredNorm();
  if (along < 0 || along > 1) return kInf;
  if (contact) *contact = b;
  return t;
}

std::vector<std::string> Tokens(const std::string& line) {
  std::istringstream is(line);
  std::vector<std::string> out;
  for (std::string t; is >> t;) out.push_back(t);
  return out;
}

double Number(const std::string& text, const std::string& path, int line) {
  const std::optional<double> v = ParseDouble(text);
  FS_THROW_UNLESS(v && std::isfinite(*v), path, ":", line, ": '", text, "' is not a finite number");
  return *v;
}

}  // namespace

double TimeToCollision(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r) {
  const double c = x.squaredNorm() - r * r;
  const double b = x.dot(v);
  if (c < 0) return b < 0 ? 0.0 : kInf;  // overlapping: collision now if approaching
  const double a = v.squaredNorm();
  if (b >= 0 || a < 1e-12) return kInf;
  const double d = b * b - a * c;
  if (d <= 0) return kInf;
  return c / (-b + std::sqrt(d));  // = (-b - sqrt d)/a, without cancellation
}

double PowerLawEnergy(double tau, double k, double exponent, double tau0) {
  if (!std::isfinite(tau)) return 0.0;
  return k * std::pow(tau, -exponent) * std::exp(-tau / tau0);
}

Eigen::Vector2d PowerLawInteractionForce(const Eigen::Vector2d& x, const Eigen::Vector2d& v,
                                         double r, double k, const PowerLawParams& p) {
  const double dist2 = x.squaredNorm();
  if (dist2 < 1e-18) return Eigen::Vector2d::Zero();
  if (dist2 < r * r) r = 0.99 * std::sqrt(dist2);  // overlap: the reference code's effective radius
  const double a = v.squaredNorm();
  const double b = x.dot(v);
  const double c = dist2 - r * r;
  if (b >= 0 || a < 1e-12) return Eigen::Vector2d::Zero();
  const double d = b * b - a * c;
  if (d <= 1e-12) return Eigen::Vector2d::Zero();
  const double sd = std::sqrt(d);
  const double tau = c / (-b + sd);
  // F = -dE/dtau grad_x tau = E (m/tau + 1/tau0) * (-(v + (b v - a x)/sqrt d)/a).
  return -ForceFactor(tau, k, p) * (v + (b * v - a * x) / sd) / a;
}

double WallTimeToCollision(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r,
                           const SimWall& w) {
  const double radius = r + w.half_thickness;
  double t = std::min(TimeToCollision(x - w.p, v, radius), TimeToCollision(x - w.q, v, radius));
  return std::min(t, BodyTimeToCollision(x, v, r, w, nullptr));
}

Eigen::Vector2d WallInteractionForce(const Eigen::Vector2d& x, const Eigen::Vector2d& v, double r,
                                     const SimWall& w, const PowerLawParams& p) {
  const double radius = r + w.half_thickness;
  BodyContact contact;
  const double t_body = BodyTimeToCollision(x, v, r, w, &contact);
  const double t_p = TimeToCollision(x - w.p, v, radius);
  const double t_q = TimeToCollision(x - w.q, v, radius);
  const double t = std::min({t_body, t_p, t_q});
  if (!std::isfinite(t)) return Eigen::Vector2d::Zero();
  if (t == t_body) {
    // tau = (s - R)/w with s = (x - p).n and w = -v.n: grad_x tau = n / w.
    const double approach = -v.dot(contact.n);
    return ForceFactor(t, p.wall_k, p) * contact.n / approach;
  }
  return PowerLawInteractionForce(x - (t == t_p ? w.p : w.q), v, radius, p.wall_k, p);
}

std::vector<SimWall> ScenarioWalls(const CrowdScenarioConfig& s) {
  std::vector<SimWall> walls;
  for (const auto& w : s.walls)
    walls.push_back({{w.x0, w.y0}, {w.x1, w.y1}, 0.5 * s.wall_thickness});
  if (s.extent.size() == 4) {
    const double x0 = s.extent[0], x1 = s.extent[1], y0 = s.extent[2], y1 = s.extent[3];
    walls.push_back({{x0, y0}, {x1, y0}, 0});
    walls.push_back({{x1, y0}, {x1, y1}, 0});
    walls.push_back({{x1, y1}, {x0, y1}, 0});
    walls.push_back({{x0, y1}, {x0, y0}, 0});
  }
  return walls;
}

// --------------------------------------------------------------------------------------------
PowerLawCrowd::PowerLawCrowd(const CrowdScenarioConfig& scenario, std::uint64_t seed)
    : scenario_(scenario), walls_(ScenarioWalls(scenario)), rng_(seed) {
  scenario_.Validate("crowd scenario '" + scenario_.name + "'");
  FS_THROW_UNLESS(scenario_.source == CrowdSource::kSimulated, "crowd scenario '", scenario_.name,
                  "': PowerLawCrowd needs source: simulated");
  const PowerLawParams& p = scenario_.power_law;
  const Eigen::Vector2d robot_start(scenario_.robot_start[0], scenario_.robot_start[1]);
  const double robot_clearance =
      scenario_.robot_radius + 0.2 + std::sqrt(2.0) * scenario_.start_jitter;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (std::size_t g = 0; g < scenario_.groups.size(); ++g) {
    const PedestrianGroupConfig& group = scenario_.groups[g];
    const double r = group.radius > 0 ? group.radius : scenario_.pedestrian_radius;
    for (int k = 0; k < group.count; ++k) {
      Eigen::Vector2d pos;
      bool placed = false;
      for (int attempt = 0; attempt < 2000 && !placed; ++attempt) {
        pos = SampleBox(group.spawn);
        placed = (pos - robot_start).norm() >= r + robot_clearance;
        for (std::size_t j = 0; j < agents_.size() && placed; ++j)
          placed = (pos - agents_[j].position).norm() >= r + agents_[j].radius;
        for (const SimWall& w : walls_) {
          if (!placed) break;
          placed = DistanceToSegment(pos, w.p, w.q) >= r + w.half_thickness;
        }
      }
      FS_THROW_UNLESS(
          placed, "crowd scenario '", scenario_.name, "': groups[", g, "] cannot place pedestrian ",
          k + 1, " of ", group.count, " of radius ", r,
          " in its spawn box without overlapping another pedestrian, a wall or the robot start");
      CrowdAgent agent;
      agent.id = static_cast<std::int64_t>(agents_.size());
      agent.position = pos;
      agent.radius = r;
      agents_.push_back(agent);
      State st;
      st.group = static_cast<int>(g);
      const double jitter = group.speed_jitter * (2 * u01(rng_) - 1);
      st.preferred_speed = std::clamp(group.preferred_speed + jitter, 0.05, p.max_speed);
      st.target = SampleBox(group.goal);
      state_.push_back(st);
    }
  }
  accel_.resize(agents_.size());
}

Eigen::Vector2d PowerLawCrowd::SampleBox(const std::vector<double>& box) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double ux = u01(rng_), uy = u01(rng_);
  return {box[0] + ux * (box[1] - box[0]), box[2] + uy * (box[3] - box[2])};
}

std::vector<Eigen::Vector2d> PowerLawCrowd::Accelerations(const RobotAgent& robot) const {
  std::vector<Eigen::Vector2d> out(agents_.size());
  ComputeAccelerations(robot, &out);
  return out;
}

void PowerLawCrowd::ComputeAccelerations(const RobotAgent& robot,
                                         std::vector<Eigen::Vector2d>* accel) const {
  const PowerLawParams& p = scenario_.power_law;
  const double range2 = p.neighbor_dist * p.neighbor_dist;
  std::vector<Eigen::Vector2d>& out = *accel;
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    const CrowdAgent& a = agents_[i];
    const State& st = state_[i];
    const Eigen::Vector2d to_target = st.target - a.position;
    const double dist = to_target.norm();
    // One-way pedestrians slow down over the last 0.5 m (and stand at their goal).
    const bool one_way = !scenario_.groups[st.group].round_trip;
    const double scale = one_way ? std::max(dist, 0.5) : std::max(dist, 1e-9);
    const Eigen::Vector2d desired = st.preferred_speed * to_target / scale;
    Eigen::Vector2d f = (desired - a.velocity) / p.relaxation;
    for (std::size_t j = 0; j < agents_.size(); ++j) {
      if (j == i) continue;
      const Eigen::Vector2d x = a.position - agents_[j].position;
      if (x.squaredNorm() > range2) continue;
      f += PowerLawInteractionForce(x, a.velocity - agents_[j].velocity,
                                    a.radius + agents_[j].radius, p.k, p);
    }
    if (robot.present && robot.position.allFinite() && robot.velocity.allFinite()) {
      const Eigen::Vector2d x = a.position - robot.position;
      if (x.squaredNorm() <= range2)
        f += PowerLawInteractionForce(x, a.velocity - robot.velocity, a.radius + robot.radius, p.k,
                                      p);
    }
    for (const SimWall& w : walls_) {
      Eigen::Vector2d closest;
      const double d = DistanceToSegment(a.position, w.p, w.q, &closest);
      if (d > p.neighbor_dist) continue;
      f += WallInteractionForce(a.position, a.velocity, a.radius, w, p);
      const double depth = a.radius + w.half_thickness - d;
      if (depth > 0 && d > 1e-9) f += p.wall_contact_stiffness * depth * (a.position - closest) / d;
    }
    out[i] = f;
  }
}

void PowerLawCrowd::Substep(double h, const RobotAgent& robot) {
  const PowerLawParams& p = scenario_.power_law;
  ComputeAccelerations(robot, &accel_);  // no allocation per substep
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    CrowdAgent& a = agents_[i];
    a.velocity = CapNorm(a.velocity + h * CapNorm(accel_[i], p.max_accel), p.max_speed);
    const Eigen::Vector2d previous = a.position;
    a.position += h * a.velocity;
    // No penetration: project out of every wall and drop the inward velocity.
    for (const SimWall& w : walls_) {
      Eigen::Vector2d closest;
      const double d = DistanceToSegment(a.position, w.p, w.q, &closest);
      const double radius = a.radius + w.half_thickness;
      if (d >= radius) continue;
      Eigen::Vector2d n =
          d > 1e-9 ? Eigen::Vector2d((a.position - closest) / d) : Eigen::Vector2d::Zero();
      if (d <= 1e-9) {
        const BodyContact b = Body(previous, w);
        n = b.valid ? b.n : Eigen::Vector2d(1, 0);
      }
      a.position = closest + radius * n;
      const double vn = a.velocity.dot(n);
      if (vn < 0) a.velocity -= vn * n;
    }
  }
  // Targets: round trips turn around, one-way pedestrians arrive.
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    State& st = state_[i];
    if ((st.target - agents_[i].position).norm() >= goal_tolerance()) continue;
    const PedestrianGroupConfig& group = scenario_.groups[st.group];
    if (group.round_trip) {
      st.to_goal = !st.to_goal;
      st.target = SampleBox(st.to_goal ? group.goal : group.spawn);
    } else {
      st.arrived = true;
    }
  }
}

void PowerLawCrowd::Step(double dt, const RobotAgent& robot) {
  FS_THROW_UNLESS(std::isfinite(dt) && dt > 0,
                  "Crowd::Step: dt must be a positive finite number, got ", dt);
  const int n = std::max(1, static_cast<int>(std::ceil(dt / scenario_.power_law.substep - 1e-9)));
  for (int s = 0; s < n; ++s) Substep(dt / n, robot);
  time_ += dt;
}

// --------------------------------------------------------------------------------------------
CrowdScenarioConfig ReadImplicitCrowdsScenario(const std::string& path) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open implicit-crowds scenario file");
  std::vector<std::pair<int, std::vector<std::string>>> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::vector<std::string> t = Tokens(line);  // '\r' of CRLF files is whitespace to >>
    if (!t.empty()) lines.emplace_back(number, std::move(t));
  }
  FS_THROW_UNLESS(lines.size() >= 3, path,
                  ": expected 'xmin xmax', 'ymin ymax' and the agent count, got ", lines.size(),
                  " non-empty lines");
  auto expect = [&](std::size_t i, std::size_t n, const char* what) {
    FS_THROW_UNLESS(lines[i].second.size() == n, path, ":", lines[i].first, ": expected ", n,
                    " fields (", what, "), got ", lines[i].second.size());
  };
  expect(0, 2, "xmin xmax");
  expect(1, 2, "ymin ymax");
  expect(2, 1, "number of agents");
  CrowdScenarioConfig s;
  s.name = std::filesystem::path(path).stem().string();
  s.source = CrowdSource::kSimulated;
  s.extent = {Number(lines[0].second[0], path, lines[0].first),
              Number(lines[0].second[1], path, lines[0].first),
              Number(lines[1].second[0], path, lines[1].first),
              Number(lines[1].second[1], path, lines[1].first)};
  const std::optional<long long> count = ParseInteger(lines[2].second[0]);
  FS_THROW_UNLESS(count && *count >= 1, path, ":", lines[2].first, ": '", lines[2].second[0],
                  "' is not a positive agent count");
  // lines.size() >= 3 here; 3 + *count could overflow for a huge count.
  FS_THROW_UNLESS(lines.size() - 3 == static_cast<unsigned long long>(*count), path,
                  ": the header announces ", *count, " agents but the file has ", lines.size() - 3,
                  " agent lines");
  s.walls.clear();
  s.groups.clear();
  double max_speed = 0;
  for (long long a = 0; a < *count; ++a) {
    expect(3 + a, 7, "gid x y goal_x goal_y pref_speed radius");
    const auto& [number, t] = lines[3 + a];
    std::vector<double> v;
    for (std::size_t f = 1; f < 7; ++f) v.push_back(Number(t[f], path, number));
    FS_THROW_UNLESS(v[4] > 0 && v[5] > 0, path, ":", number,
                    ": preferred speed and radius must be positive");
    PedestrianGroupConfig g;
    g.count = 1;
    g.spawn = {v[0], v[0], v[1], v[1]};
    g.goal = {v[2], v[2], v[3], v[3]};
    g.preferred_speed = v[4];
    g.speed_jitter = 0;
    g.radius = v[5];
    g.round_trip = false;
    s.groups.push_back(g);
    max_speed = std::max(max_speed, v[4]);
  }
  s.power_law = PowerLawParams{};
  s.power_law.max_speed = 1.5 * max_speed;
  s.pedestrian_radius = s.groups.front().radius;
  s.robot_start = {s.extent[0] + 1, s.extent[2] + 1, 0};
  s.robot_goal = {s.extent[1] - 1, s.extent[3] - 1};
  s.Validate(path);
  return s;
}

PowerLawParams ReadImplicitCrowdsParameters(const std::string& path, PowerLawParams base) {
  std::ifstream in(path);
  FS_THROW_UNLESS(in.good(), path, ": cannot open implicit-crowds parameter file");
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find('=');
    FS_THROW_UNLESS(eq != std::string::npos, path, ":", number, ": expected key=value, got '", line,
                    "'");
    const std::string key = line.substr(0, eq);
    const double value = Number(line.substr(eq + 1), path, number);
    if (key == "k")
      base.k = value;
    else if (key == "p")
      base.exponent = value;
    else if (key == "t0")
      base.tau0 = value;
    else if (key == "neighborDist")
      base.neighbor_dist = value;
    else if (key == "ksi" || key == "eps" || key == "repulsive" || key == "newtonIter" ||
             key == "eps_x" || key == "lbfgsWindow")
      continue;  // implicit-integrator settings without a counterpart in the force-based model
    else
      Fail(path, ":", number, ": unknown key '", key, "'");
    FS_THROW_UNLESS(value > 0, path, ":", number, ": '", key, "' must be positive, got ", value);
  }
  return base;
}

}  // namespace foresight
