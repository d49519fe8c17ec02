#include "training/otnet/data.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/log.h"
#include "datasets/data_root.h"
#include "datasets/synthetic_rooms.h"
#include "inference/otnet/trajectory_metrics.h"

namespace foresight::otnet {

int OtnetSplit::trajectories() const {
  int n = 0;
  for (const MapTrajectories& m : maps) n += static_cast<int>(m.trajectories.size());
  return n;
}

std::vector<MapTrajectories> OtnetSplit::OriginalMaps() const {
  return {maps.begin(), maps.end() - copies};
}

MapTrajectories TransformMap(const MapTrajectories& m, int s, int* dropped) {
  FS_THROW_UNLESS(s >= 0 && s < 8, "otnet: symmetry ", s, " is not in [0, 8)");
  const int n = m.map.width;
  FS_THROW_UNLESS(m.map.height == n, "otnet: map ", m.id, " is ", m.map.width, " x ", m.map.height,
                  "; symmetric copies need a square map");
  const bool swap = (s & 4) != 0, flip_x = (s & 1) != 0, flip_y = (s & 2) != 0;
  MapTrajectories out;
  out.id = s == 0 ? m.id : m.id + "@s" + std::to_string(s);
  out.map = BinaryGrid(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      int x = swap ? r : c, y = swap ? c : r;  // the source cell's column and row after the swap
      if (flip_x) x = n - 1 - x;
      if (flip_y) y = n - 1 - y;
      out.map.at(y, x) = m.map.at(r, c);
    }
  for (const Eigen::MatrixX2d& t : m.trajectories) {
    Eigen::MatrixX2d u(t.rows(), 2);
    u.col(0) = swap ? t.col(1) : t.col(0);
    u.col(1) = swap ? t.col(0) : t.col(1);
    if (flip_x) u.col(0) = (n - u.col(0).array()).matrix();
    if (flip_y) u.col(1) = (n - u.col(1).array()).matrix();
    bool free = true;
    for (Eigen::Index k = 0; k < u.rows() && free; ++k)
      free = !out.map.OccupiedAt(u(k, 0), u(k, 1));
    if (free)
      out.trajectories.push_back(std::move(u));
    else
      ++*dropped;
  }
  return out;
}

void AugmentDihedral(OtnetSplit* split) {
  const std::size_t originals = split->maps.size() - split->copies;
  split->maps.reserve(8 * originals);
  int dropped = 0;
  for (int s = 1; s < 8; ++s)
    for (std::size_t i = 0; i < originals; ++i) {
      split->maps.push_back(TransformMap(split->maps[i], s, &dropped));
      ++split->copies;
    }
  if (dropped > 0)
    log::Warn("otnet data: ", dropped,
              " trajectories of the symmetric copies dropped (a waypoint "
              "on a cell boundary next to an occupied cell lands in it when reflected)");
}

namespace {

void Truncate(MapTrajectories* m, int max_trajectories) {
  if (max_trajectories > 0 && static_cast<int>(m->trajectories.size()) > max_trajectories)
    m->trajectories.resize(max_trajectories);
}

void LogSplit(const char* name, const OtnetSplit& s) {
  const ReadReport& r = s.report;
  log::Info("otnet data: ", name, ": ", s.maps.size(), " maps, ", s.trajectories(), " trajectories",
            r.trajectories > 0 ? "" : " (synthetic)",
            s.copies > 0 ? " (" + std::to_string(s.copies) + " maps are symmetric copies)" : "");
  if (r.dropped_outside + r.dropped_occupied + r.dropped_too_short > 0)
    log::Warn("otnet data: ", name, ": dropped ", r.dropped_outside,
              " trajectories with a waypoint outside the map, ", r.dropped_occupied,
              " with a waypoint in an occupied cell, ", r.dropped_too_short,
              " with fewer than 2 waypoints (of ", r.trajectories, " read)");
}

}  // namespace

OtnetData LoadOtnetData(const ExperimentConfig& c) {
  const double val = c.data.val_fraction, test = c.data.test_fraction;
  const auto seed = static_cast<std::uint64_t>(c.seed);
  OtnetData d;
  if (c.data.source == Source::kSynthetic) {
    SyntheticRoomsOptions o;
    o.size = c.data.map_size;
    o.maps = c.data.synthetic_maps;
    o.trajectories_per_map = c.data.synthetic_trajectories;
    o.layouts = c.data.synthetic_layouts;
    o.seed = seed;
    std::vector<MapTrajectories> all = GenerateRoomsAndCorridors(o);
    // Maps of one layout family are near-copies: split families, not maps, so that the
    // validation and test maps are layouts never trained on.
    const int families = o.layouts > 0 ? std::min(o.layouts, o.maps) : o.maps;
    std::vector<std::string> ids;
    for (int k = 0; k < families; ++k) ids.push_back("family_" + std::to_string(k));
    const MapSplit split = SplitMaps(ids, val, test, seed);
    const auto take = [&](const std::vector<std::string>& part, OtnetSplit* out) {
      for (const std::string& id : part) {
        const int family = std::stoi(id.substr(7));
        for (int k = family; k < static_cast<int>(all.size()); k += families) {
          MapTrajectories& m = all[k];
          Truncate(&m, c.data.max_trajectories);
          out->maps.push_back(m);
        }
      }
    };
    take(split.train, &d.train);
    take(split.val, &d.val);
    take(split.test, &d.test);
  } else {
    const std::string root = ResolveDataFile(c.data.root, "occ_traj120");
    std::vector<std::string> ids = ListOccTrajMaps(root);
    std::sort(ids.begin(), ids.end());
    if (c.data.max_maps > 0 && static_cast<int>(ids.size()) > c.data.max_maps)
      ids.resize(c.data.max_maps);
    const MapSplit split = SplitMaps(ids, val, test, seed);
    const BadWaypointPolicy policy = c.data.bad_waypoints == BadWaypoints::kError
                                         ? BadWaypointPolicy::kError
                                         : BadWaypointPolicy::kDrop;
    const auto read = [&](const std::vector<std::string>& part, OtnetSplit* out) {
      for (const std::string& id : part) {
        ReadReport r;
        MapTrajectories m = LoadOccTrajMap(root, id, c.data.map_size, policy, &r);
        Truncate(&m, c.data.max_trajectories);
        out->report.Add(r);
        out->maps.push_back(std::move(m));
      }
    };
    read(split.train, &d.train);
    read(split.val, &d.val);
    read(split.test, &d.test);
  }
  if (c.data.augment == Augment::kDihedral) AugmentDihedral(&d.train);
  LogSplit("train", d.train);
  LogSplit("val", d.val);
  LogSplit("test", d.test);
  FS_THROW_UNLESS(d.train.trajectories() > 0, "otnet data: the training maps hold no trajectories");
  FS_THROW_UNLESS(d.val.trajectories() > 0,
                  "otnet data: the validation maps hold no trajectories (raise data.val_fraction)");
  FS_THROW_UNLESS(d.test.trajectories() > 0,
                  "otnet data: the test maps hold no trajectories (raise data.test_fraction)");
  return d;
}

TrajectoryBasis MakeBasis(const ExperimentConfig& c) {
  return TrajectoryBasis(c.otnet.basis, c.otnet.basis_gamma, c.otnet.ridge);
}

std::vector<int> ChooseDatabase(const std::vector<MapTrajectories>& maps, int database_size) {
  const int n = static_cast<int>(maps.size());
  std::vector<int> chosen;
  if (database_size <= 0 || database_size >= n) {
    for (int i = 0; i < n; ++i) chosen.push_back(i);
    return chosen;
  }
  std::vector<std::vector<Eigen::Vector2i>> edges(n);
  std::vector<std::vector<float>> fields(n);
  for (int i = 0; i < n; ++i) {
    const BinaryGrid& g = maps[i].map;
    edges[i] = EdgeCells(g);
    EdgeDistanceField(edges[i], g.width, g.height, &fields[i]);
  }
  // Greedy k-centre: each next map is the one farthest (delta_H) from the chosen ones.
  std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
  int next = 0;
  for (int k = 0; k < database_size; ++k) {
    chosen.push_back(next);
    const int width = maps[next].map.width;
    int far = -1;
    double far_d = -1;
    for (int i = 0; i < n; ++i) {
      const double d = 0.5 * (OneSidedHausdorff(edges[i], fields[next], width) +
                              OneSidedHausdorff(edges[next], fields[i], width));
      nearest[i] = std::min(nearest[i], d);
      if (nearest[i] > far_d) {
        far_d = nearest[i];
        far = i;
      }
    }
    if (far_d <= 0) {
      log::Warn("otnet: only ", chosen.size(), " distinct maps for a database of ", database_size,
                "; using those");
      break;
    }
    next = far;
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

MapEncoder MakeEncoder(const ExperimentConfig& c, const OtnetSplit& train) {
  const std::vector<MapTrajectories> read = train.OriginalMaps();
  std::vector<BinaryGrid> database;
  for (int i : ChooseDatabase(read, c.otnet.database_size)) database.push_back(read[i].map);
  return MapEncoder(std::move(database), c.otnet.length_scale);
}

EncodedSplit EncodeSplit(const MapEncoder& encoder, const TrajectoryBasis& basis,
                         const OtnetSplit& split) {
  EncodedSplit e;
  const int maps = static_cast<int>(split.maps.size());
  e.phi.resize(maps, encoder.size());
  e.w.resize(split.trajectories(), basis.weights());
  MapEncoder::Workspace ws = encoder.MakeWorkspace();
  Eigen::VectorXd phi(encoder.size());
  int row = 0;
  for (int m = 0; m < maps; ++m) {
    encoder.Encode(split.maps[m].map, &ws, phi);
    e.phi.row(m) = phi.transpose();
    for (const Eigen::MatrixX2d& t : split.maps[m].trajectories) {
      e.w.row(row++) = basis.Fit(ResampleUniform(t, kFitPoints)).transpose();
      e.map_index.push_back(m);
    }
  }
  return e;
}

double ReconstructionRmse(const TrajectoryBasis& basis, const OtnetSplit& split) {
  double sum = 0;
  long count = 0;
  for (const MapTrajectories& m : split.maps)
    for (const Eigen::MatrixX2d& t : m.trajectories) {
      const Eigen::MatrixX2d r = ResampleUniform(t, kFitPoints);
      sum += (basis.Evaluate(basis.Fit(r), UniformTaus(kFitPoints)) - r).squaredNorm();
      count += kFitPoints;
    }
  return count ? std::sqrt(sum / count) : 0.0;
}

}  // namespace foresight::otnet
