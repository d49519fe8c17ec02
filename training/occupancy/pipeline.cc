#include "training/occupancy/pipeline.h"

#include <Eigen/Cholesky>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "core/file_io.h"
#include "core/log.h"
#include "datasets/carmen.h"
#include "datasets/data_root.h"
#include "inference/mapping/fusion.h"
#include "inference/mapping/grid_map.h"
#include "inference/mapping/hinge_map.h"
#include "models/occupancy/bhm.h"
#include "models/occupancy/coupled_bhm.h"
#include "models/occupancy/fast_bhm.h"
#include "models/occupancy/grid_builder.h"
#include "models/occupancy/hilbert_map.h"
#include "models/occupancy/scan_training.h"
#include "training/occupancy/plots.h"

namespace foresight::occupancy {
namespace fs = std::filesystem;

namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string Json(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

std::string MetricsJson(const BinaryMetrics& m) {
  return "{\"auc\": " + Json(m.auc) + ", \"precision\": " + Json(m.precision) +
         ", \"recall\": " + Json(m.recall) + "}";
}

void WriteRoc(const Map& map, const LabelledPoints& test, int points, const std::string& path) {
  MapWorkspace ws = map.MakeWorkspace();
  std::vector<double> scores(test.size());
  for (std::int64_t i = 0; i < test.size(); ++i)
    scores[i] = map.Probability(test.xy(0, i), test.xy(1, i), &ws);
  std::ostringstream out;
  out << "false_positive_rate,true_positive_rate\n";
  for (const auto& [fpr, tpr] : RocCurve(scores, test.occupied, points))
    out << fpr << "," << tpr << "\n";
  WriteFileAtomically(path, out.str());
}

}  // namespace

std::vector<LaserScan> Data::TrainScanList() const {
  std::vector<LaserScan> out;
  out.reserve(train_scans.size());
  for (const int s : train_scans) out.push_back(scans[s]);
  return out;
}

Data LoadData(const ExperimentConfig& c) {
  const DataConfig& d = c.data;
  FS_THROW_UNLESS(d.test_offset < d.test_every, "data.test_offset ", d.test_offset,
                  " must be smaller than data.test_every ", d.test_every);
  Data data;
  if (d.format == ScanSource::kCarmen) {
    FS_THROW_UNLESS(!d.file.empty(), "data.file: no CARMEN log given (format: carmen)");
    const std::string path = ResolveDataFile(d.root, d.file);
    FS_THROW_UNLESS(fs::exists(path), path,
                    ": CARMEN log not found (set data.root or $FORESIGHT_DATA)");
    data.scans = ReadCarmenLog(path);
  } else {
    const FloorPlan plan = GenerateFloorPlan(d.synthetic, static_cast<std::uint64_t>(c.seed));
    data.scans = SimulateRobots(plan, d.synthetic, static_cast<std::uint64_t>(c.seed));
  }
  data.points = SampleLabelledPoints(data.scans, d.points, static_cast<std::uint64_t>(c.seed));
  const ScanSplit split =
      SplitEveryKth(static_cast<int>(data.scans.size()), d.test_every, d.test_offset);
  data.test_scans = split.test;
  for (std::size_t i = 0; i < split.train.size(); i += d.train_scan_stride) {
    const auto k = i / d.train_scan_stride;
    if (d.val_every > 0 && k % d.val_every == static_cast<std::size_t>(d.val_every - 1)) {
      data.val_scans.push_back(split.train[i]);
    } else {
      data.train_scans.push_back(split.train[i]);
    }
  }
  FS_THROW_UNLESS(!data.train_scans.empty() && !data.test_scans.empty(),
                  "data: ", data.scans.size(), " scans leave ", data.train_scans.size(),
                  " training and ", data.test_scans.size(),
                  " test scans; need at least one of each");
  data.train = SelectScans(data.points, data.train_scans);
  data.test = SelectScans(data.points, data.test_scans);
  if (!data.val_scans.empty()) data.val = SelectScans(data.points, data.val_scans);
  log::Info("occupancy data: ", data.scans.size(), " scans, ", data.points.size(),
            " labelled points (", data.points.dropped_beams, " beams dropped); train ",
            data.train_scans.size(), " scans / ", data.train.size(), " points, val ",
            data.val_scans.size(), " scans, test ", data.test_scans.size(), " scans / ",
            data.test.size(), " points");
  return data;
}

namespace {

/// The coupled learner on `scans` of `points`, fitted (bound updates logged, and returned).
std::unique_ptr<CoupledBhmLearner> FitCoupledBhm(const HingeGrid& grid, const FastBhmConfig& f,
                                                 const LabelledPoints& points,
                                                 const std::vector<int>& scans,
                                                 std::vector<BoundUpdateReport>* reports) {
  auto learner =
      std::make_unique<CoupledBhmLearner>(grid, CoupledBhmOptions{f.prior_mean, f.prior_variance});
  for (const int s : scans) {
    const auto b = points.scan_begin[s], e = points.scan_begin[s + 1];
    try {
      learner->Add(points.xy.middleCols(b, e - b), points.occupied.data() + b);
    } catch (const Error& err) {  // the learner counts its own scans; name the data's
      Fail("training scan ", s, ": ", err.what());
    }
  }
  const std::vector<BoundUpdateReport> r = learner->Fit(f.bound_updates);
  for (const BoundUpdateReport& u : r)
    log::Info("coupled Fast-BHM: bound update ", u.update, ": ELBO ", u.elbo, ", mean |dz| ",
              u.mean_abs_dz, ", ", u.seconds, " s");
  if (reports) *reports = r;
  return learner;
}

std::string BoundReportsJson(const std::vector<BoundUpdateReport>& reports) {
  std::ostringstream os;
  os << "[";
  for (std::size_t i = 0; i < reports.size(); ++i)
    os << (i ? ", " : "") << "{\"update\": " << reports[i].update
       << ", \"elbo\": " << Json(reports[i].elbo)
       << ", \"mean_abs_dz\": " << Json(reports[i].mean_abs_dz)
       << ", \"seconds\": " << Json(reports[i].seconds) << "}";
  return os.str() + "]";
}

}  // namespace

std::unique_ptr<Map> TrainMap(const std::string& model, const ExperimentConfig& c, const Data& data,
                              double* seconds, std::vector<BoundUpdateReport>* bound_reports) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<Map> map;
  const bool coupled = c.fast_bhm.update == FastBhmUpdate::kCoupled;
  if (model == kFastBhmType && coupled) {
    const auto learner = FitCoupledBhm(HingeGrid(c.features), c.fast_bhm, data.train,
                                       FirstScans(data.train), bound_reports);
    map = std::make_unique<HingeMap>(learner->ToMap());
  } else if (model == kFastBhmType) {
    FastBhmLearner learner(HingeGrid(c.features), c.fast_bhm);
    UpdateOnScans(&learner, data.train, FirstScans(data.train));
    map = std::make_unique<HingeMap>(learner.ToMap());
  } else if (model == kBhmType && coupled) {
    // The full BHM with the coupled learner's bound: the same posterior, kept with its full
    // covariance (dense inverse of the sparse precision; small grids only).
    const HingeGrid grid(c.features);
    FS_THROW_UNLESS(grid.size() <= 4096, "model: ", kBhmType, " keeps a dense covariance of ",
                    grid.size(), " features; use at most 4096 (features.spacing)");
    const auto learner =
        FitCoupledBhm(grid, c.fast_bhm, data.train, FirstScans(data.train), bound_reports);
    const SparseInformation info = learner->DataInformation();
    Eigen::MatrixXd precision = Eigen::MatrixXd(info.precision_data);
    precision = precision.selfadjointView<Eigen::Lower>();
    precision.diagonal().array() += 1.0 / c.fast_bhm.prior_variance;
    HingeWeights w;
    w.mean = learner->mean();
    w.covariance = precision.llt().solve(Eigen::MatrixXd::Identity(grid.size(), grid.size()));
    w.variance = w.covariance.diagonal();
    map = std::make_unique<HingeMap>(HingeMapKind::kBhm, grid, std::move(w), c.fast_bhm.prior_mean,
                                     c.fast_bhm.prior_variance);
  } else if (model == kBhmType) {
    BhmLearner learner(HingeGrid(c.features), c.fast_bhm);
    UpdateOnScans(&learner, data.train, FirstScans(data.train));
    map = std::make_unique<HingeMap>(learner.ToMap());
  } else if (model == kHilbertMapType) {
    map = std::make_unique<HingeMap>(TrainHilbertMap(HingeGrid(c.features), c.hilbert,
                                                     data.train.xy, data.train.occupied.data(),
                                                     static_cast<std::uint64_t>(c.seed)));
  } else if (model == kGridMapType) {
    map = std::make_unique<GridMap>(BuildGridMap(c.grid, data.TrainScanList()));
  } else {
    Fail("model '", model, "' is not an occupancy map kind (occupancy.fast_bhm, occupancy.bhm, ",
         "occupancy.hilbert, occupancy.grid)");
  }
  if (seconds) *seconds = Seconds(start);
  return map;
}

void SaveMap(const Map& map, const std::string& path, const ExperimentConfig& c) {
  const std::string yaml = config::ToYaml(c);
  if (const auto* h = dynamic_cast<const HingeMap*>(&map)) {
    h->Save(path, yaml, c.seed, c.precision);
  } else if (const auto* g = dynamic_cast<const GridMap*>(&map)) {
    g->Save(path, yaml, c.seed);
  } else {
    Fail("cannot save a map of type ", map.model_type());
  }
}

std::int64_t ArtifactBytes(const Map& map, const ExperimentConfig& c) {
  const fs::path tmp =
      fs::temp_directory_path() /
      ("foresight_artifact_size_" + std::to_string(reinterpret_cast<std::uintptr_t>(&map)) + ".h5");
  SaveMap(map, tmp.string(), c);
  const auto bytes = static_cast<std::int64_t>(fs::file_size(tmp));
  fs::remove(tmp);
  return bytes;
}

BinaryMetrics EvaluateMap(const Map& map, const LabelledPoints& points) {
  MapWorkspace ws = map.MakeWorkspace();
  std::vector<double> scores(points.size());
  for (std::int64_t i = 0; i < points.size(); ++i)
    scores[i] = map.Probability(points.xy(0, i), points.xy(1, i), &ws);
  return EvaluateBinary(scores, points.occupied, 0.5);
}

FusionResult RunFusion(const ExperimentConfig& c, const Data& data) {
  const HingeGrid grid(c.features);
  FusionResult r;
  // Robots: lists of indices into data.train's scans, in recording order.
  std::vector<std::vector<int>> robots;
  if (c.fusion.robots == FusionExperimentConfig::Robots::kQuadrants) {
    const auto q =
        QuadrantSplit(data.train, FirstScans(data.train), c.fusion.centre_x, c.fusion.centre_y);
    for (const auto& list : q)
      if (!list.empty()) robots.push_back(list);
  } else {
    int max_robot = 0;
    for (const int id : data.train.robot) max_robot = std::max(max_robot, id);
    robots.resize(max_robot + 1);
    for (int s = 0; s < data.train.num_scans(); ++s) robots[data.train.robot[s]].push_back(s);
    robots.erase(
        std::remove_if(robots.begin(), robots.end(), [](const auto& l) { return l.empty(); }),
        robots.end());
  }
  FS_THROW_UNLESS(robots.size() >= 2, "fusion: the training scans belong to ", robots.size(),
                  " robot(s); need at least two (check fusion.robots / centre)");
  for (const auto& l : robots) r.robot_scans.push_back(static_cast<int>(l.size()));

  std::vector<std::string> names;
  for (std::size_t i = 0; i < robots.size(); ++i) names.push_back("robot " + std::to_string(i));
  if (c.fast_bhm.update == FastBhmUpdate::kCoupled) {
    // The learning map: single map; fuse once exactly (sum of the robots' sparse information,
    // each at its own learned bounds) and approximately (conflation of their diagonal maps).
    r.single = std::make_unique<HingeMap>(
        FitCoupledBhm(grid, c.fast_bhm, data.train, FirstScans(data.train), nullptr)->ToMap());
    std::vector<SparseInformation> parts;
    std::vector<HingeMap> locals;
    for (const auto& scans : robots) {
      const auto l = FitCoupledBhm(grid, c.fast_bhm, data.train, scans, nullptr);
      parts.push_back(l->DataInformation());
      locals.push_back(l->ToMap());
      r.information_bytes.push_back(static_cast<std::int64_t>(parts.back().Bytes()));
    }
    r.fuse_once = std::make_unique<HingeMap>(CoupledBhmLearner::FuseInformation(
        grid, CoupledBhmOptions{c.fast_bhm.prior_mean, c.fast_bhm.prior_variance}, parts));
    std::vector<const HingeMap*> ptrs;
    for (const auto& l : locals) ptrs.push_back(&l);
    r.conflated = std::make_unique<HingeMap>(FuseMaps(ptrs, names, c.fusion.options));
    return r;
  }
  FastBhmLearner single(grid, c.fast_bhm);
  UpdateOnScans(&single, data.train, FirstScans(data.train));
  r.single = std::make_unique<HingeMap>(single.ToMap());

  // Fuse once: independent local maps on all of each robot's data, one conflation.
  std::vector<HingeMap> locals;
  for (const auto& scans : robots) {
    FastBhmLearner l(grid, c.fast_bhm);
    UpdateOnScans(&l, data.train, scans);
    locals.push_back(l.ToMap());
  }
  std::vector<const HingeMap*> ptrs;
  for (const auto& l : locals) ptrs.push_back(&l);
  r.fuse_once = std::make_unique<HingeMap>(FuseMaps(ptrs, names, c.fusion.options));

  // Repeated fusion (thesis Algorithm "Fast-BHM Sequential Fusion"): after each 1/merges of every
  // robot's data, each robot's copy is merged; copies restart from the new global map.
  std::unique_ptr<HingeMap> global;
  const int merges = c.fusion.merges;
  for (int m = 0; m < merges; ++m) {
    std::vector<HingeMap> copies;
    for (const auto& scans : robots) {
      const std::size_t b = scans.size() * m / merges, e = scans.size() * (m + 1) / merges;
      const std::vector<int> chunk(scans.begin() + b, scans.begin() + e);
      FastBhmLearner l =
          global ? FastBhmLearner(*global, c.fast_bhm) : FastBhmLearner(grid, c.fast_bhm);
      UpdateOnScans(&l, data.train, chunk);
      copies.push_back(l.ToMap());
    }
    std::vector<const HingeMap*> cp;
    for (const auto& x : copies) cp.push_back(&x);
    global = std::make_unique<HingeMap>(FuseMaps(cp, names, c.fusion.options, global.get()));
  }
  r.repeated = std::move(global);
  return r;
}

void TrainRun(const ExperimentConfig& c, const std::string& run_dir) {
  StartRunDirectory(run_dir, config::ToYaml(c), false, kOccupancyRunRules);
  const Data data = LoadData(c);
  const std::string artifact = run_dir + "/model.h5";
  const auto start = std::chrono::steady_clock::now();
  if (c.model == "occupancy.fusion") {
    const FusionResult r = RunFusion(c, data);
    SaveMap(*r.single, run_dir + "/single.h5", c);
    SaveMap(*r.fuse_once, run_dir + "/fuse_once.h5", c);
    if (r.conflated) SaveMap(*r.conflated, run_dir + "/conflated.h5", c);
    // The run's map: the exactly fused learning map (coupled), else the repeated fusion.
    SaveMap(r.repeated ? *r.repeated : *r.fuse_once, artifact, c);
    std::ostringstream out;
    out << "{\"seconds\": " << Json(Seconds(start)) << ", \"robots\": " << r.robot_scans.size()
        << ", \"robot_scans\": [";
    for (std::size_t i = 0; i < r.robot_scans.size(); ++i)
      out << (i ? ", " : "") << r.robot_scans[i];
    out << "], \"information_bytes\": [";
    for (std::size_t i = 0; i < r.information_bytes.size(); ++i)
      out << (i ? ", " : "") << r.information_bytes[i];
    out << "]";
    if (r.repeated) out << ", \"merges\": " << c.fusion.merges;  // coupled fuses once
    out << "}\n";
    WriteFileAtomically(run_dir + "/training_summary.json", out.str());
  } else {
    double secs = 0;
    std::vector<BoundUpdateReport> bounds;
    const std::unique_ptr<Map> map = TrainMap(c.model, c, data, &secs, &bounds);
    SaveMap(*map, artifact, c);
    std::ostringstream out;
    out << "{\"seconds\": " << Json(secs) << ", \"bound_updates\": " << BoundReportsJson(bounds)
        << "}\n";
    WriteFileAtomically(run_dir + "/training_summary.json", out.str());
    log::Info(c.model, ": trained in ", secs, " s");
  }
}

std::string EvaluateRun(const ExperimentConfig& c, const std::string& run_dir) {
  const std::string artifact = run_dir + "/model.h5";
  FS_THROW_UNLESS(fs::exists(artifact), artifact, ": not found (train the map first)");
  const Data data = LoadData(c);
  fs::create_directories(run_dir + "/plots");
  std::ostringstream json;
  json << "{\n  \"model\": \"" << c.model << "\",\n  \"train_scans\": " << data.train_scans.size()
       << ",\n  \"test_scans\": " << data.test_scans.size()
       << ",\n  \"train_points\": " << data.train.size()
       << ",\n  \"test_points\": " << data.test.size() << ",\n";
  if (c.model == "occupancy.fusion") {
    // Evaluates what ships: the maps as loaded from their artifacts.
    // coupled: single, fuse_once (sparse information, exact), fuse_once_conflation (diagonal
    // maps, approximate); published: single, fuse_once and repeated (conflation both).
    const bool coupled = c.fast_bhm.update == FastBhmUpdate::kCoupled;
    const std::vector<std::pair<std::string, std::string>> files =
        coupled
            ? std::vector<std::pair<std::string, std::string>>{{"single", "single.h5"},
                                                               {"fuse_once", "fuse_once.h5"},
                                                               {"fuse_once_conflation",
                                                                "conflated.h5"}}
            : std::vector<std::pair<std::string, std::string>>{
                  {"single", "single.h5"}, {"fuse_once", "fuse_once.h5"}, {"repeated", "model.h5"}};
    std::vector<std::unique_ptr<Map>> maps;
    std::vector<MapPanel> panels;
    json << "  \"update\": \"" << (coupled ? "coupled" : "published") << "\"";
    if (!coupled) json << ",\n  \"merges\": " << c.fusion.merges;  // coupled fuses once
    BinaryMetrics last;
    for (const auto& [name, file] : files) {
      maps.push_back(LoadMap(run_dir + "/" + file));
      last = EvaluateMap(*maps.back(), data.test);
      json << ",\n  \"auc_" << name << "\": " << Json(last.auc) << ",\n  \"" << name
           << "\": " << MetricsJson(last) << ",\n  \"" << name
           << "_bytes\": " << fs::file_size(run_dir + "/" + file);
      panels.push_back({name, maps.back().get()});
      log::Info("fusion: ", name, " AUC ", last.auc);
    }
    const BinaryMetrics shipped = EvaluateMap(*LoadMap(artifact), data.test);
    json << ",\n  \"auc\": " << Json(shipped.auc)
         << ",\n  \"precision\": " << Json(shipped.precision)
         << ",\n  \"recall\": " << Json(shipped.recall)
         << ",\n  \"artifact_bytes\": " << fs::file_size(artifact) << "\n}\n";
    WriteMapPanels(panels, c.eval.plot_resolution, run_dir + "/plots/map.png");
  } else {
    const std::unique_ptr<Map> loaded = LoadMap(artifact);  // evaluate what ships
    const BinaryMetrics m = EvaluateMap(*loaded, data.test);
    json << "  \"auc\": " << Json(m.auc) << ",\n  \"precision\": " << Json(m.precision)
         << ",\n  \"recall\": " << Json(m.recall)
         << ",\n  \"artifact_bytes\": " << fs::file_size(artifact);
    if (data.val.size() > 0)
      json << ",\n  \"val\": " << MetricsJson(EvaluateMap(*loaded, data.val));
    json << "\n}\n";
    WriteRoc(*loaded, data.test, c.eval.roc_points, run_dir + "/roc.csv");
    WriteMapPanels({{c.model, loaded.get()}}, c.eval.plot_resolution, run_dir + "/plots/map.png");
    log::Info(c.model, ": AUC ", m.auc, ", precision ", m.precision, ", recall ", m.recall);
  }
  WriteFileAtomically(run_dir + "/eval.json", json.str());
  return json.str();
}

}  // namespace foresight::occupancy
