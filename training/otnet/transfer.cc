#include "training/otnet/transfer.h"

#include <random>

#include "core/error.h"
#include "core/log.h"
#include "training/otnet/plots.h"

namespace foresight::otnet {

std::vector<Eigen::Vector2d> BorderOpenings(const BinaryGrid& g, int count) {
  // Walk the perimeter once (clockwise from the top-left cell) and collect runs of free cells.
  std::vector<Eigen::Vector2i> ring;  // (col, row)
  for (int c = 0; c < g.width; ++c) ring.emplace_back(c, 0);
  for (int r = 1; r < g.height; ++r) ring.emplace_back(g.width - 1, r);
  for (int c = g.width - 2; c >= 0; --c) ring.emplace_back(c, g.height - 1);
  for (int r = g.height - 2; r >= 1; --r) ring.emplace_back(0, r);
  const int n = static_cast<int>(ring.size());
  const auto free_at = [&](int i) {
    const Eigen::Vector2i& p = ring[((i % n) + n) % n];
    return g.at(p.y(), p.x()) == 0;
  };
  int first = 0;  // start the walk on an occupied cell so that no run wraps around
  while (first < n && free_at(first)) ++first;
  std::vector<std::pair<int, Eigen::Vector2d>> runs;  // (length, inward centre)
  if (first == n) return {Eigen::Vector2d(g.width / 2.0, g.height / 2.0)};
  for (int i = first + 1; i <= first + n;) {
    if (!free_at(i)) {
      ++i;
      continue;
    }
    int j = i;
    while (j < first + n && free_at(j)) ++j;
    const Eigen::Vector2i mid = ring[((i + j - 1) / 2) % n];
    // One cell inward from the border, at the cell centre.
    Eigen::Vector2d centre(mid.x() + 0.5, mid.y() + 0.5);
    if (mid.y() == 0) centre.y() += 1;
    if (mid.y() == g.height - 1) centre.y() -= 1;
    if (mid.x() == 0) centre.x() += 1;
    if (mid.x() == g.width - 1) centre.x() -= 1;
    runs.emplace_back(j - i, centre);
    i = j;
  }
  std::stable_sort(runs.begin(), runs.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Eigen::Vector2d> out;
  for (int k = 0; k < count && k < static_cast<int>(runs.size()); ++k)
    out.push_back(runs[k].second);
  return out;
}

BinaryGrid RasteriseSection(const foresight::occupancy::Map& map, double x_min, double y_min,
                            double side, int size, double threshold) {
  FS_THROW_UNLESS(side > 0 && size > 0, "RasteriseSection: side ", side, " and size ", size,
                  " must be positive");
  BinaryGrid g(size, size);
  occupancy::MapWorkspace ws = map.MakeWorkspace();
  const double cell = side / size;
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c)
      g.at(r, c) =
          map.Probability(x_min + (c + 0.5) * cell, y_min + (r + 0.5) * cell, &ws) >= threshold;
  return g;
}

Scores TransferToOccupancyMap(const ExperimentConfig& c, const OtnetModel& model,
                              const OtnetSplit& train, const std::string& plot_png) {
  const TransferConfig& t = c.transfer;
  FS_THROW_UNLESS(!t.sections.empty() && t.sections.size() % 3 == 0,
                  "transfer.sections: ", t.sections.size(),
                  " numbers; expected x_min, y_min, side per section");
  FS_THROW_UNLESS(t.starts.size() % 2 == 0 && t.openings >= 1, "transfer.starts: ", t.starts.size(),
                  " numbers; expected x, y pairs");
  const std::unique_ptr<foresight::occupancy::Map> occupancy =
      occupancy::LoadMap(t.occupancy_artifact);
  const int size = model.encoder().width();
  std::vector<BinaryGrid> train_maps;
  for (const MapTrajectories& m : train.maps) train_maps.push_back(m.map);
  const MapEncoder knn(train_maps, c.otnet.length_scale);
  MapEncoder::Workspace knn_ws = knn.MakeWorkspace();
  OtnetModel::Workspace ws = model.MakeWorkspace(t.generated, c.eval.points);
  GenerateOptions gen;
  gen.count = t.generated;
  gen.points = c.eval.points;
  gen.max_attempts = std::max(c.eval.max_attempts, t.generated);
  gen.check_step = c.eval.check_step;

  const int sections = static_cast<int>(t.sections.size() / 3);
  std::vector<BinaryGrid> grids(sections);
  const int per_section = t.starts.empty() ? t.openings : static_cast<int>(t.starts.size() / 2);
  std::vector<std::vector<TrajectoryPanel>> rows(per_section + 1);
  long accepted = 0, attempts = 0;
  for (int s = 0; s < sections; ++s) {
    const double x0 = t.sections[3 * s], y0 = t.sections[3 * s + 1], side = t.sections[3 * s + 2];
    grids[s] = RasteriseSection(*occupancy, x0, y0, side, size, t.threshold);
    FS_THROW_UNLESS(!EdgeCells(grids[s]).empty(), "transfer.sections[", s, "] (", x0, ", ", y0,
                    ", ", side, "): no occupied edge in the section; choose another");
    const Mixture& mixture = model.Predict(grids[s], &ws);
    std::vector<Eigen::Vector2d> starts;
    if (t.starts.empty()) {
      starts = BorderOpenings(grids[s], t.openings);
      if (starts.empty()) {
        log::Warn("otnet transfer: section ", s,
                  " has no opening in its border; starting at its "
                  "centre");
        starts.emplace_back(size / 2.0, size / 2.0);
      }
    } else
      for (std::size_t k = 0; k + 1 < t.starts.size(); k += 2)
        starts.emplace_back(t.starts[k], t.starts[k + 1]);
    for (std::size_t k = 0; k < starts.size(); ++k) {
      Eigen::Vector2d start = starts[k];
      if (grids[s].OccupiedAt(start.x(), start.y())) {
        const Eigen::Vector2d moved = NearestFreeCentre(grids[s], start);
        log::Info("otnet transfer: section ", s, ": start (", start.x(), ", ", start.y(),
                  ") is occupied; moved to (", moved.x(), ", ", moved.y(), ")");
        start = moved;
      }
      model.ConditionOnStart(mixture, start, ComponentSelection::kNearest, &ws.conditioned);
      std::mt19937_64 rng(static_cast<std::uint64_t>(c.seed) + 1000 * s + k);
      const GenerateStats st = model.Generate(grids[s], ws.conditioned, gen, &rng, &ws);
      accepted += st.accepted;
      attempts += st.attempts;
      TrajectoryPanel p;
      p.map = &grids[s];
      p.generated.assign(ws.generated.begin(), ws.generated.begin() + st.accepted);
      p.has_start = true;
      p.start = start;
      p.title = "section " + std::to_string(s) + ": OTNet, " + std::to_string(st.accepted) + "/" +
                std::to_string(st.attempts) + " collision-free";
      if (st.accepted < 10) {
        // Show what the model proposes even where the check rejects it (drawn orange).
        GenerateOptions raw = gen;
        raw.reject_collisions = false;
        raw.count = std::min(gen.count, 10);
        const GenerateStats rs = model.Generate(grids[s], ws.conditioned, raw, &rng, &ws);
        p.colliding.assign(ws.generated.begin(), ws.generated.begin() + rs.accepted);
      }
      rows[k].push_back(p);
    }
    const int nearest = knn.Nearest(grids[s], &knn_ws);
    TrajectoryPanel p;
    p.map = &grids[s];
    p.generated = train.maps[nearest].trajectories;
    if (p.generated.size() > 30) p.generated.resize(30);
    p.title = "k-NN: " + train.maps[nearest].id;
    rows.back().push_back(p);
  }
  if (!plot_png.empty()) DrawTrajectoryPanels(rows, plot_png);
  return {{"transfer_sections", sections},
          {"transfer_acceptance_rate", attempts ? static_cast<double>(accepted) / attempts : 0.0}};
}

}  // namespace foresight::otnet
