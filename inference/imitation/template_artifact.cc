#include "inference/imitation/template_artifact.h"

#include <cmath>
#include <vector>

#include "core/error.h"
#include "inference/engine/artifact.h"

namespace foresight::imitation {
namespace {

template <int D>
Vec<D> ReadVec(const h5::File& f, const std::string& name) {
  const Eigen::MatrixXd m = f.ReadMatrixD(name, D, 1);
  FS_THROW_UNLESS(m.allFinite(), f.path(), ": dataset '", name, "' is not finite");
  return m.col(0);
}

// The relative round-trip tolerance of the load-time invertibility check.
constexpr double kRoundTripTolerance = 1e-8;

}  // namespace

template <int D>
void SaveTemplate(const std::string& path, const ImitationSystem<D>& system,
                  const TemplateNormalisation& normalisation, const std::string& config_yaml,
                  std::int64_t seed) {
  FS_THROW_UNLESS(normalisation.offset.size() == D && normalisation.offset.allFinite(), path,
                  ": normalisation offset has ", normalisation.offset.size(),
                  " entries (finite ones expected: ", D, ")");
  FS_THROW_UNLESS(std::isfinite(normalisation.scale) && normalisation.scale > 0, path,
                  ": normalisation scale ", normalisation.scale, " must be positive and finite");
  const RbfFlow<D>& flow = system.flow();
  const RbfGridSpec<D>& g = flow.grid().spec();
  h5::WriteAtomically(path, [&](h5::File* f) {
    Artifact::WriteHeader(f, kTemplateModelType, config_yaml, seed);
    f->SetAttr("/model", "dimension", std::int64_t{D});
    f->SetAttr("/model", "steps", std::int64_t{flow.settings().steps});
    f->SetAttr("/model", "time", flow.settings().time);
    f->SetAttr("/model", "segments", std::int64_t{flow.settings().segments});
    f->SetAttr("/model", "speed", system.speed());
    f->SetAttr("/model", "gamma", g.gamma);
    f->SetAttr("/model", "cutoff_radius", g.cutoff_radius);
    f->SetAttr("/model", "spacing", g.spacing);
    f->Write("/model/lower", g.lower.data(), {D});
    std::int64_t counts[D];
    for (int a = 0; a < D; ++a) counts[a] = g.counts[a];
    f->Write("/model/counts", counts, {D});
    f->WriteMatrix("/model/weights", flow.weights());
    f->Write("/model/goal", system.goal().data(), {D});
    f->Write("/normalisation/offset", normalisation.offset.data(), {D});
    f->SetAttr("/normalisation", "scale", normalisation.scale);
  });
}

int TemplateDimension(const std::string& path) {
  const Artifact a = Artifact::Open(path, kTemplateModelType);
  return a.IntAttr("/model", "dimension", 2, 3);
}

template <int D>
Eigen::Matrix<double, D, Eigen::Dynamic> InvertibilityCheckPoints(const RbfGrid<D>& grid) {
  const RbfGridSpec<D>& g = grid.spec();
  const int cap = D == 2 ? 45 : 13;  // 2025 and 2197 points
  int n[D];
  long total = 1;
  for (int a = 0; a < D; ++a) {
    n[a] = std::max(2, std::min(cap, 2 * g.counts[a] - 1));
    total *= n[a];
  }
  Eigen::Matrix<double, D, Eigen::Dynamic> points(D, total);
  for (long p = 0; p < total; ++p) {
    long rest = p;
    for (int a = 0; a < D; ++a) {
      // Cell centres shifted by an irrational fraction: never exactly on a cut-off sphere or a
      // symmetry plane of the grid (the inverse oscillates there at the truncation level).
      const double extent = g.spacing * (g.counts[a] - 1);
      points(a, p) = g.lower[a] + extent * (static_cast<double>(rest % n[a]) + 0.381966) / n[a];
      rest /= n[a];
    }
  }
  return points;
}

template <int D>
TemplateArtifact<D> LoadTemplate(const std::string& path) {
  Artifact a = Artifact::Open(path, kTemplateModelType);
  const h5::File& f = a.file();
  const int dimension = a.IntAttr("/model", "dimension", 2, 3);
  FS_THROW_UNLESS(dimension == D, path, ": attribute /model/dimension is ", dimension,
                  "; this loader reads ", D, "-D templates");
  FlowSettings<D> settings;
  settings.steps = a.IntAttr("/model", "steps", 1, 100000);
  settings.time = a.DoubleAttr("/model", "time", 1e-12, 1e6);
  // Absent in templates written before segments existed: one stationary field.
  settings.segments =
      f.HasAttr("/model", "segments") ? a.IntAttr("/model", "segments", 1, settings.steps) : 1;
  const double speed = a.DoubleAttr("/model", "speed", 1e-12, 1e12);
  RbfGridSpec<D> spec;
  spec.gamma = a.DoubleAttr("/model", "gamma", 1e-12, 1e12);
  spec.cutoff_radius = a.DoubleAttr("/model", "cutoff_radius", 1e-12, 1e12);
  spec.spacing = a.DoubleAttr("/model", "spacing", 1e-12, 1e12);
  spec.lower = ReadVec<D>(f, "/model/lower");
  const h5::Array<std::int64_t> counts = f.ReadInt("/model/counts");
  FS_THROW_UNLESS(counts.shape.size() == 1 && counts.shape[0] == D, path,
                  ": dataset '/model/counts' has ", counts.Size(), " entries, expected ", D);
  for (int a_ = 0; a_ < D; ++a_) {
    const std::int64_t c = counts.data[static_cast<std::size_t>(a_)];
    FS_THROW_UNLESS(c >= 1 && c <= (1 << 22), path, ": dataset '/model/counts' entry ", a_, " is ",
                    c, "; expected 1 to ", 1 << 22);
    spec.counts[a_] = static_cast<int>(c);
  }
  TemplateArtifact<D> out;
  try {
    RbfGrid<D> grid(spec, path + ": /model grid");
    Eigen::MatrixXd weights = f.ReadMatrixD("/model/weights", settings.segments * grid.size(), D);
    FS_THROW_UNLESS(weights.allFinite(), path, ": dataset '/model/weights' is not finite");
    const Vec<D> goal = ReadVec<D>(f, "/model/goal");
    out.normalisation.offset = ReadVec<D>(f, "/normalisation/offset");
    out.normalisation.scale = a.DoubleAttr("/normalisation", "scale", 1e-300, 1e300);
    RbfFlow<D> flow(grid, std::move(weights), settings, path + ": /model/weights");
    const double tolerance = kRoundTripTolerance + flow.TruncationAllowance();
    const InvertibilityReport report =
        CheckInvertible(flow, InvertibilityCheckPoints(grid), tolerance);
    FS_THROW_UNLESS(report.ok, path, ": the flow (/model/weights, steps ", settings.steps,
                    ", segments ", settings.segments, ", time ", settings.time,
                    ") is not invertible over the grid: ", report.Describe());
    out.system = ImitationSystem<D>(std::move(flow), goal, speed);
  } catch (const Error& e) {
    const std::string what = e.what();
    if (what.rfind(path, 0) == 0) throw;
    Fail(path, ": ", what);
  }
  out.config_yaml = a.config_yaml();
  out.seed = a.seed();
  return out;
}

template void SaveTemplate<2>(const std::string&, const ImitationSystem<2>&,
                              const TemplateNormalisation&, const std::string&, std::int64_t);
template void SaveTemplate<3>(const std::string&, const ImitationSystem<3>&,
                              const TemplateNormalisation&, const std::string&, std::int64_t);
template TemplateArtifact<2> LoadTemplate<2>(const std::string&);
template TemplateArtifact<3> LoadTemplate<3>(const std::string&);
template Eigen::Matrix<double, 2, Eigen::Dynamic> InvertibilityCheckPoints<2>(const RbfGrid<2>&);
template Eigen::Matrix<double, 3, Eigen::Dynamic> InvertibilityCheckPoints<3>(const RbfGrid<3>&);

}  // namespace foresight::imitation
