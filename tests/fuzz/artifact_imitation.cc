// Fuzz target: LoadTemplate<2>, LoadTemplate<3> (inference/imitation/template_artifact.h) and
// EFlowModel::Load (inference/imitation/eflow.h) on edited valid artifacts written by SaveTemplate
// and EFlowModel::Save (tests/fuzz/h5_mutator.h); the first input byte picks the artifact. A model
// that loads must give finite velocities at finite states.
#include <cmath>
#include <random>

#include "inference/imitation/eflow.h"
#include "inference/imitation/template_artifact.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"

namespace {

using namespace foresight;
using namespace foresight::imitation;

template <int D>
std::vector<std::uint8_t> TemplateBase() {
  RbfGridSpec<D> s;
  s.lower = Vec<D>::Constant(-0.6);
  s.counts.fill(D == 2 ? 5 : 4);
  s.spacing = D == 2 ? 0.3 : 0.4;
  s.gamma = D == 2 ? 30 : 20;
  s.cutoff_radius = D == 2 ? 0.8 : 1.0;
  const RbfGrid<D> grid(s);
  std::mt19937_64 rng(D);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd w(grid.size(), D);
  for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = 0.02 * n01(rng);
  const ImitationSystem<D> system(RbfFlow<D>(grid, w, FlowSettings<D>{1.0, 4}),
                                  Vec<D>::Constant(0.1), 0.8);
  TemplateNormalisation norm;
  norm.offset = Eigen::VectorXd::LinSpaced(D, -1.5, 2.0);
  norm.scale = 0.25;
  const std::string path = fuzz::ScratchPath(D == 2 ? "base_template2.h5" : "base_template3.h5");
  SaveTemplate<D>(path, system, norm, "model: diffeo_template\n", 0);
  return fuzz::ReadFileBytes(path);
}

std::vector<std::uint8_t> EFlowBase() {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int d = 2, features = 3;
  std::vector<EFlowCouplingLayer> layers;
  for (int l = 0; l < 2; ++l) {
    EFlowCouplingLayer layer;
    layer.transformed = l % d;
    layer.omega = Eigen::MatrixXd::NullaryExpr(features, d - 1, [&] { return normal(rng); });
    layer.phase = Eigen::VectorXd::NullaryExpr(features, [&] { return 3 * normal(rng); });
    layer.scale = Eigen::VectorXd::NullaryExpr(features, [&] { return 0.15 * normal(rng); });
    layer.translate = Eigen::VectorXd::NullaryExpr(features, [&] { return 0.3 * normal(rng); });
    layers.push_back(std::move(layer));
  }
  const EFlowModel model(d, std::move(layers), Eigen::Vector2d(0.1, -0.2), 1.7);
  const std::string path = fuzz::ScratchPath("base_eflow.h5");
  model.Save(path, "model: diffeo_eflow\n", 0);
  return fuzz::ReadFileBytes(path);
}

template <int D>
void CheckTemplate(const std::string& path) {
  const TemplateArtifact<D> a = LoadTemplate<D>(path);
  FlowWorkspace<D> ws = a.system.flow().MakeWorkspace();
  bool finite = a.normalisation.offset.allFinite() && std::isfinite(a.normalisation.scale);
  for (const double c : {-0.5, 0.05, 0.4}) {
    Vec<D> z;
    const Vec<D> v = a.system.Velocity(Vec<D>::Constant(c), &ws, &z);
    finite = finite && v.allFinite() && z.allFinite();
  }
  fuzz::ExpectFiniteAnswer(finite, path, "a template velocity");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::uint8_t> bases[] = {TemplateBase<2>(), TemplateBase<3>(),
                                                    EFlowBase()};
  fuzz::ByteReader in(data, size);
  const int kind = in.Byte() % 3;
  const std::string path =
      fuzz::WriteScratch("imitation.h5", bases[kind].data(), bases[kind].size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    if (kind == 0) {
      CheckTemplate<2>(path);
    } else if (kind == 1) {
      CheckTemplate<3>(path);
    } else {
      const EFlowModel model = EFlowModel::Load(path);
      const Eigen::VectorXd x = Eigen::VectorXd::Constant(model.dimension(), 0.3);
      Eigen::MatrixXd j;
      const Eigen::VectorXd z = model.Forward(x, &j);
      const Eigen::VectorXd v = model.Velocity(x);
      fuzz::ExpectFiniteAnswer(
          z.allFinite() && j.allFinite() && v.allFinite() && model.Inverse(z).allFinite(), path,
          "an eflow velocity");
    }
  });
  return 0;
}
