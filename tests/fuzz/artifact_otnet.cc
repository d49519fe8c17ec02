// Fuzz target: OtnetModel::Load on edited valid otnet artifacts written by OtnetModel::Save
// (tests/fuzz/h5_mutator.h; Normal and Laplace mixtures, picked by the first input byte). A model
// that loads must predict a finite mixture and finite position marginals for a valid map.
#include <cmath>
#include <random>

#include "inference/otnet/otnet_model.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"

namespace {

using namespace foresight;
using namespace foresight::otnet;

constexpr int kSide = 8, kBasis = 3, kComponents = 2;

BinaryGrid Room(int variant) {
  BinaryGrid g(kSide, kSide);
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c)
      g.at(r, c) = (r == 0 || c == 0 || r == kSide - 1 || c == kSide - 1) ? 1 : 0;
  g.at(3, 2 + variant) = 1;
  return g;
}

std::vector<std::uint8_t> Base(MixtureFamily family) {
  std::mt19937_64 rng(family == MixtureFamily::kNormal ? 1 : 2);
  std::normal_distribution<float> n01;
  const OtnetHead head{kComponents, 2 * kBasis};
  auto layer = [&](int rows, int cols) {
    DenseLayer l;
    l.weight = Eigen::MatrixXf::NullaryExpr(rows, cols, [&] { return 0.4f * n01(rng); });
    l.bias = Eigen::VectorXf::NullaryExpr(rows, [&] { return 0.2f * n01(rng); });
    return l;
  };
  OtnetModel model(MapEncoder({Room(0), Room(1), Room(2)}, 5.0),
                   TrajectoryBasis(kBasis, 10.0, 1e-3), Mlp({layer(4, 3), layer(head.Total(), 4)}),
                   family, kComponents);
  if (family == MixtureFamily::kLaplace)
    model.SetLogScaleOffset(Eigen::VectorXd::Constant(2 * kBasis, -0.5));
  const std::string path =
      fuzz::ScratchPath(family == MixtureFamily::kNormal ? "base_otnet_n.h5" : "base_otnet_l.h5");
  model.Save(path, "model: otnet\n", 0);
  return fuzz::ReadFileBytes(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::uint8_t> bases[] = {Base(MixtureFamily::kNormal),
                                                    Base(MixtureFamily::kLaplace)};
  fuzz::ByteReader in(data, size);
  const int kind = in.Byte() % 2;
  const std::string path = fuzz::WriteScratch("otnet.h5", bases[kind].data(), bases[kind].size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    const OtnetModel model = OtnetModel::Load(path);
    OtnetModel::Workspace ws = model.MakeWorkspace(4, 5);
    const BinaryGrid map = Room(1);
    const BinaryGrid& first = model.encoder().database().front();
    if (map.width != first.width || map.height != first.height) return;  // a query error
    const Mixture& m = model.Predict(map, &ws);
    bool finite = m.alpha.allFinite() && m.mean.allFinite() && m.scale.allFinite();
    const Eigen::VectorXd taus = Eigen::VectorXd::LinSpaced(4, 0.0, 1.0);
    Eigen::MatrixX2d mean;
    Eigen::MatrixXd cov_x, cov_y;
    for (int q = 0; q < m.components(); ++q) {
      model.ComponentMarginals(m, q, taus, &mean, &cov_x, &cov_y);
      finite = finite && mean.allFinite() && cov_x.allFinite() && cov_y.allFinite();
    }
    fuzz::ExpectFiniteAnswer(finite, path, "the predicted mixture");
  });
  return 0;
}
