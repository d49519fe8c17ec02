// Occupancy-map reproductions of thesis ch 3 on a CARMEN log (default: Intel), one run:
//  1. every map kind (Fast-BHM, Hilbert map, grid float32 / uint8, OctoMap) on the every-10th-scan
//     split, and in the sparse case (train on every 10th training scan, same test scans);
//  2. size against quality: artifact bytes vs AUC for Fast-BHM at several feature spacings, grids
//  at
//     several resolutions, and the fusion of discretised Fast-BHM outputs by a log-odds grid update
//     (four quadrant robots) at several resolutions.
// Writes OUT/occupancy_intel.md, OUT/occupancy_size_quality.csv and OUT/occupancy_size_quality.png.
//
// Usage: occupancy_experiments [--config configs/occupancy/intel.yaml] [--out results]

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"
#include "inference/mapping/fusion.h"
#include "inference/mapping/grid_map.h"
#include "inference/mapping/hinge_map.h"
#include "models/occupancy/fast_bhm.h"
#include "models/occupancy/scan_training.h"
#include "training/occupancy/octomap_baseline.h"
#include "training/occupancy/pipeline.h"

namespace fs = std::filesystem;
using namespace foresight;

namespace {

struct Row {
  std::string method;
  double parameter;  // spacing or resolution (m)
  std::int64_t bytes;
  double auc;
};

occupancy::ExperimentConfig WithSpacing(occupancy::ExperimentConfig c, double spacing) {
  const double k = spacing / c.features.spacing;
  c.features.gamma /= k * k;  // keep the overlap of neighbouring features
  c.features.cutoff_radius *= k;
  c.features.spacing = spacing;
  return c;
}

/// A Fast-BHM trained on the listed scans of `points`, in order.
occupancy::HingeMap TrainOnScans(const occupancy::ExperimentConfig& c, const LabelledPoints& points,
                                 const std::vector<int>& scans) {
  occupancy::FastBhmLearner l(HingeGrid(c.features), c.fast_bhm);
  occupancy::UpdateOnScans(&l, points, scans);
  return l.ToMap();
}

/// Log-odds fusion of discretised map outputs (the grid update rule the thesis compares against).
occupancy::GridMap FuseDiscretised(const std::vector<const occupancy::Map*>& maps,
                                   const occupancy::GridMapConfig& g, occupancy::CellType type) {
  occupancy::GridGeometry geo;
  geo.x_min = g.x_min;
  geo.y_min = g.y_min;
  geo.resolution = g.resolution;
  geo.nx = static_cast<int>(std::ceil((g.x_max - g.x_min) / g.resolution - 1e-9));
  geo.ny = static_cast<int>(std::ceil((g.y_max - g.y_min) / g.resolution - 1e-9));
  Eigen::MatrixXf p(geo.ny, geo.nx);
  std::vector<occupancy::MapWorkspace> ws;
  for (const auto* m : maps) ws.push_back(m->MakeWorkspace());
  const double l_max = std::log(g.p_max / (1 - g.p_max)), l_min = std::log(g.p_min / (1 - g.p_min));
  for (int iy = 0; iy < geo.ny; ++iy)
    for (int ix = 0; ix < geo.nx; ++ix) {
      const double x = geo.x_min + (ix + 0.5) * geo.resolution,
                   y = geo.y_min + (iy + 0.5) * geo.resolution;
      double l = 0;
      for (std::size_t k = 0; k < maps.size(); ++k) {
        const double q = std::clamp(maps[k]->Probability(x, y, &ws[k]), 1e-6, 1 - 1e-6);
        l += std::log(q / (1 - q));
      }
      l = std::clamp(l, l_min, l_max);
      p(iy, ix) = static_cast<float>(1 / (1 + std::exp(-l)));
    }
  return occupancy::GridMap(geo, std::move(p), type);
}

void PlotCurves(const std::vector<Row>& rows, const std::string& path) {
  const int w = 900, h = 560, left = 70, bottom = 60, top = 30, right = 220;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  double bmin = 1e18, bmax = 0, amin = 1, amax = 0;
  for (const auto& r : rows) {
    bmin = std::min(bmin, double(r.bytes));
    bmax = std::max(bmax, double(r.bytes));
    amin = std::min(amin, r.auc);
    amax = std::max(amax, r.auc);
  }
  amin = std::floor(amin * 50) / 50;
  amax = std::min(1.0, std::ceil(amax * 50) / 50);
  const double lb0 = std::floor(std::log10(bmin)), lb1 = std::ceil(std::log10(bmax));
  auto px = [&](double bytes) {
    return left + int((std::log10(bytes) - lb0) / (lb1 - lb0) * (w - left - right));
  };
  auto py = [&](double auc) {
    return h - bottom - int((auc - amin) / (amax - amin) * (h - bottom - top));
  };
  cv::rectangle(img, {left, top}, {w - right, h - bottom}, {0, 0, 0});
  for (double e = lb0; e <= lb1; e += 1) {
    cv::putText(img, "1e" + std::to_string(int(e)), {px(std::pow(10, e)) - 12, h - bottom + 20},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  }
  for (double a = amin; a <= amax + 1e-9; a += 0.02) {
    std::ostringstream s;
    s.precision(2);
    s << std::fixed << a;
    cv::putText(img, s.str(), {15, py(a) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  }
  cv::putText(img, "artifact bytes (log)", {w / 2 - 120, h - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.55,
              {0, 0, 0});
  cv::putText(img, "AUC", {15, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0});
  const std::vector<cv::Scalar> colours{{200, 60, 20},  {30, 30, 200}, {30, 150, 30},
                                        {150, 30, 150}, {0, 140, 220}, {90, 90, 90}};
  std::map<std::string, std::vector<Row>> by;
  for (const auto& r : rows) by[r.method].push_back(r);
  int k = 0;
  for (auto& [name, list] : by) {
    std::sort(list.begin(), list.end(),
              [](const Row& a, const Row& b) { return a.bytes < b.bytes; });
    const cv::Scalar col = colours[k % colours.size()];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const cv::Point p(px(list[i].bytes), py(list[i].auc));
      cv::circle(img, p, 4, col, cv::FILLED);
      if (i > 0) cv::line(img, {px(list[i - 1].bytes), py(list[i - 1].auc)}, p, col, 2);
    }
    cv::putText(img, name, {w - right + 10, top + 20 + 22 * k}, cv::FONT_HERSHEY_SIMPLEX, 0.5, col,
                2);
    ++k;
  }
  FS_THROW_UNLESS(cv::imwrite(path, img), path, ": cannot write PNG");
}

}  // namespace

int main(int argc, char** argv) try {
  std::string config_path = "configs/occupancy/intel.yaml", out = "results";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--config")
      config_path = argv[i + 1];
    else if (k == "--out")
      out = argv[i + 1];
    else
      Fail("unknown option ", k, " (use --config FILE --out DIR)");
  }
  fs::create_directories(out);
  const occupancy::ExperimentConfig base =
      config::LoadExperimentConfig<occupancy::ExperimentConfig>(config_path, {});
  std::ostringstream md;
  md << "# Occupancy maps on `" << base.data.file
     << "` (measured by `build/bin/occupancy_experiments --config " << config_path << "`)\n\n";

  // 0. The Fast-BHM updates: as published (decoupled, z = 1) against the coupled learning map,
  // with spacing and bound updates chosen on validation scans (every 10th training scan held
  // out), never on the test scans; then the chosen settings trained on every training scan.
  {
    occupancy::ExperimentConfig v = base;
    v.data.val_every = 10;
    const occupancy::Data vdata = occupancy::LoadData(v);
    md << "## Fast-BHM updates (validation: every 10th training scan held out)\n\n"
       << "| update | spacing (m) | bound updates | val AUC |\n|---|---|---|---|\n";
    double best_auc = -1, best_spacing = 0;
    int best_updates = 0;
    for (const double spacing : {0.4, 0.5, 0.6}) {
      occupancy::ExperimentConfig c = WithSpacing(v, spacing);
      c.fast_bhm.update = occupancy::FastBhmUpdate::kPublished;
      const auto published = occupancy::TrainMap(occupancy::kFastBhmType, c, vdata);
      md << "| published | " << spacing << " | (z = 1) | "
         << occupancy::EvaluateMap(*published, vdata.val).auc << " |\n";
      c.fast_bhm.update = occupancy::FastBhmUpdate::kCoupled;
      for (const int updates : {0, 2, 5}) {
        c.fast_bhm.bound_updates = updates;
        const double auc = occupancy::EvaluateMap(
                               *occupancy::TrainMap(occupancy::kFastBhmType, c, vdata), vdata.val)
                               .auc;
        md << "| coupled | " << spacing << " | " << updates << " | " << auc << " |\n";
        if (auc > best_auc) best_auc = auc, best_spacing = spacing, best_updates = updates;
      }
    }
    md << "\nChosen on validation: coupled, spacing " << best_spacing << " m, " << best_updates
       << " bound updates.\n\n| training data | model | AUC | bytes | train s "
          "|\n|---|---|---|---|---|\n";
    for (const int stride : {1, 10}) {
      occupancy::ExperimentConfig c = WithSpacing(base, best_spacing);
      c.data.train_scan_stride = stride;
      const occupancy::Data data = occupancy::LoadData(c);
      const std::string label = stride == 1 ? "all training scans" : "every 10th training scan";
      for (const bool coupled : {false, true}) {
        c.fast_bhm.update =
            coupled ? occupancy::FastBhmUpdate::kCoupled : occupancy::FastBhmUpdate::kPublished;
        c.fast_bhm.bound_updates = best_updates;
        double secs = 0;
        const auto map = occupancy::TrainMap(occupancy::kFastBhmType, c, data, &secs);
        md << "| " << label << " | Fast-BHM " << (coupled ? "coupled" : "published") << " ("
           << best_spacing << " m) | " << occupancy::EvaluateMap(*map, data.test).auc << " | "
           << occupancy::ArtifactBytes(*map, c) << " | " << secs << " |\n";
      }
      const occupancy::OctomapFigures o =
          occupancy::RunOctomapBaseline(data, c.data.points.max_range, 0.1, 3);
      md << "| " << label << " | OctoMap 0.1 m | " << o.auc << " | " << o.bytes << " | "
         << o.insert_s << " |\n";
    }
    // Full BHM against Fast-BHM on a grid where the dense covariance fits (1 m: 1,400 features),
    // both with the coupled posterior and the same learned bound (thesis: 0.96 vs 0.95).
    occupancy::ExperimentConfig c = WithSpacing(base, 1.0);
    c.fast_bhm.update = occupancy::FastBhmUpdate::kCoupled;
    c.fast_bhm.bound_updates = best_updates;
    const occupancy::Data data = occupancy::LoadData(c);
    for (const std::string& model :
         {std::string(occupancy::kBhmType), std::string(occupancy::kFastBhmType)}) {
      double secs = 0;
      const auto map = occupancy::TrainMap(model, c, data, &secs);
      md << "| all training scans | " << model << " coupled (1 m) | "
         << occupancy::EvaluateMap(*map, data.test).auc << " | "
         << occupancy::ArtifactBytes(*map, c) << " | " << secs << " |\n";
    }
    md << "\n";
    std::cout << "done: Fast-BHM updates\n";
  }

  // 1. Every model, full and sparse training data.
  md << "| training data | model | AUC | precision | recall | bytes | train s "
        "|\n|---|---|---|---|---|---|---|\n";
  for (const int stride : {1, 10}) {
    occupancy::ExperimentConfig c = base;
    c.fast_bhm.update =
        occupancy::FastBhmUpdate::kPublished;  // the rows below are the thesis's Fast-BHM
    c.data.train_scan_stride = stride;
    const occupancy::Data data = occupancy::LoadData(c);
    const std::string label =
        stride == 1 ? "all training scans" : "every 10th training scan (sparse)";
    for (const auto& [model, cell] : std::vector<std::pair<std::string, occupancy::CellType>>{
             {occupancy::kFastBhmType, occupancy::CellType::kFloat32},
             {occupancy::kHilbertMapType, occupancy::CellType::kFloat32},
             {occupancy::kGridMapType, occupancy::CellType::kFloat32},
             {occupancy::kGridMapType, occupancy::CellType::kUint8}}) {
      c.grid.cell_type = cell;
      double secs = 0;
      const auto map = occupancy::TrainMap(model, c, data, &secs);
      const BinaryMetrics m = occupancy::EvaluateMap(*map, data.test);
      const std::string name =
          model == occupancy::kGridMapType
              ? model + (cell == occupancy::CellType::kUint8 ? " (uint8, " : " (float32, ") +
                    std::to_string(c.grid.resolution).substr(0, 4) + " m)"
              : model;
      md << "| " << label << " | " << name << " | " << m.auc << " | " << m.precision << " | "
         << m.recall << " | " << occupancy::ArtifactBytes(*map, c) << " | " << secs << " |\n";
    }
    {
      // Fast-BHM at 0.4 m spacing: about twice OctoMap's serialized size.
      const occupancy::ExperimentConfig f = WithSpacing(c, 0.4);
      double secs = 0;
      const auto map = occupancy::TrainMap(occupancy::kFastBhmType, f, data, &secs);
      const BinaryMetrics m = occupancy::EvaluateMap(*map, data.test);
      md << "| " << label << " | occupancy.fast_bhm (0.4 m spacing) | " << m.auc << " | "
         << m.precision << " | " << m.recall << " | " << occupancy::ArtifactBytes(*map, f) << " | "
         << secs << " |\n";
    }
    const occupancy::OctomapFigures o =
        occupancy::RunOctomapBaseline(data, c.data.points.max_range, 0.1, 3);
    md << "| " << label << " | OctoMap 0.1 m | " << o.auc << " | " << o.precision << " | "
       << o.recall << " | " << o.bytes << " | " << o.insert_s << " |\n";
    std::cout << "done: " << label << "\n";
  }

  // 2. Size against quality.
  const occupancy::Data data = occupancy::LoadData(base);
  std::vector<Row> rows;
  for (const double s : {1.0, 0.75, 0.6, 0.5, 0.4, 0.3, 0.25}) {
    const occupancy::ExperimentConfig c = WithSpacing(base, s);
    const auto map = occupancy::TrainMap(occupancy::kFastBhmType, c, data);
    rows.push_back({base.fast_bhm.update == occupancy::FastBhmUpdate::kCoupled ? "Fast-BHM coupled"
                                                                               : "Fast-BHM",
                    s, occupancy::ArtifactBytes(*map, c),
                    occupancy::EvaluateMap(*map, data.test).auc});
  }
  for (const double r : {0.4, 0.3, 0.2, 0.15, 0.1, 0.05}) {
    for (const occupancy::CellType t :
         {occupancy::CellType::kFloat32, occupancy::CellType::kUint8}) {
      occupancy::ExperimentConfig c = base;
      c.grid.resolution = r;
      c.grid.cell_type = t;
      const auto map = occupancy::TrainMap(occupancy::kGridMapType, c, data);
      rows.push_back({t == occupancy::CellType::kUint8 ? "grid uint8" : "grid float32", r,
                      occupancy::ArtifactBytes(*map, c),
                      occupancy::EvaluateMap(*map, data.test).auc});
    }
  }
  {
    // Four quadrant robots, each a Fast-BHM of about 10,000 features (thesis), discretised and
    // fused.
    const double spacing = std::sqrt((base.features.x_max - base.features.x_min) *
                                     (base.features.y_max - base.features.y_min) / 10000.0);
    const occupancy::ExperimentConfig c = WithSpacing(base, spacing);
    const auto quadrants = QuadrantSplit(data.train, occupancy::FirstScans(data.train),
                                         c.fusion.centre_x, c.fusion.centre_y);
    std::vector<occupancy::HingeMap> locals;
    for (const auto& scans : quadrants) locals.push_back(TrainOnScans(c, data.train, scans));
    std::vector<const occupancy::Map*> ptrs;
    for (const auto& m : locals) ptrs.push_back(&m);
    for (const double r : {0.4, 0.3, 0.2, 0.15, 0.1}) {
      for (const occupancy::CellType t :
           {occupancy::CellType::kFloat32, occupancy::CellType::kUint8}) {
        occupancy::GridMapConfig g = base.grid;
        g.resolution = r;
        const occupancy::GridMap fused = FuseDiscretised(ptrs, g, t);
        rows.push_back({t == occupancy::CellType::kUint8 ? "discretised fusion uint8"
                                                         : "discretised fusion float32",
                        r, occupancy::ArtifactBytes(fused, base),
                        occupancy::EvaluateMap(fused, data.test).auc});
      }
    }
    for (const double s : {1.0, 0.5, 0.4, 0.3}) {
      const occupancy::ExperimentConfig cs = WithSpacing(base, s);
      std::vector<occupancy::HingeMap> qs;
      for (const auto& scans : quadrants) qs.push_back(TrainOnScans(cs, data.train, scans));
      std::vector<const occupancy::HingeMap*> qp;
      for (const auto& m : qs) qp.push_back(&m);
      const occupancy::HingeMap fused = occupancy::FuseMaps(
          qp, std::vector<std::string>(qp.size(), "quadrant"), cs.fusion.options);
      rows.push_back({"fused Fast-BHM", s, occupancy::ArtifactBytes(fused, cs),
                      occupancy::EvaluateMap(fused, data.test).auc});
    }
  }
  std::ofstream csv(out + "/occupancy_size_quality.csv");
  csv << "method,spacing_or_resolution_m,artifact_bytes,auc\n";
  md << "\n## Size against quality (artifact bytes vs AUC, every-10th-scan test split)\n\n"
     << "| method | spacing / resolution (m) | artifact bytes | AUC |\n|---|---|---|---|\n";
  for (const auto& r : rows) {
    csv << r.method << "," << r.parameter << "," << r.bytes << "," << r.auc << "\n";
    md << "| " << r.method << " | " << r.parameter << " | " << r.bytes << " | " << r.auc << " |\n";
  }
  PlotCurves(rows, out + "/occupancy_size_quality.png");
  std::ofstream(out + "/occupancy_intel.md") << md.str();
  std::cout << md.str();
  return 0;
} catch (const std::exception& e) {
  std::cerr << "occupancy_experiments: error: " << e.what() << "\n";
  return 1;
}
