// Fuzz target: EnergyModel::Load (inference/manipulation/energy_model.h) on edited valid
// gfcs_energy artifacts written by EnergyModel::Save (tests/fuzz/h5_mutator.h). A model that loads
// must give finite energies and gradients for a finite query in an empty world.
#include <cmath>
#include <random>

#include "inference/manipulation/energy_model.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/h5_mutator.h"

namespace {

using namespace foresight;
using namespace foresight::manipulation;

Mlp RandomMlp(const std::vector<int>& sizes, std::mt19937_64* rng) {
  std::normal_distribution<float> n01;
  std::vector<DenseLayer> layers;
  for (std::size_t i = 0; i + 1 < sizes.size(); ++i) {
    DenseLayer l;
    l.weight =
        Eigen::MatrixXf::NullaryExpr(sizes[i + 1], sizes[i], [&] { return 0.3f * n01(*rng); });
    l.bias = Eigen::VectorXf::NullaryExpr(sizes[i + 1], [&] { return 0.1f * n01(*rng); });
    layers.push_back(std::move(l));
  }
  return Mlp(std::move(layers));
}

std::vector<std::uint8_t> Base() {
  std::mt19937_64 rng(1);
  EnergyModelParts p;
  p.lattice.lower = Eigen::Vector3d(0, 0, 0);
  p.lattice.upper = Eigen::Vector3d(0.3, 0.3, 0.3);
  p.lattice.spacing = 0.3;
  p.lattice.max_distance = 1.0;
  p.bps_mean = Eigen::VectorXf::Constant(8, 0.4f);
  p.bps_std = Eigen::VectorXf::Constant(8, 0.2f);
  p.encoder = RandomMlp({8, 3}, &rng);
  p.intermediate_commands = 1;
  p.energy = RandomMlp({EnergyModel::kStateContext + 3 + 7, 4, 1}, &rng);
  p.lower << -2.9, -1.76, -2.9, -3.07, -2.9, -0.02, -2.9;
  p.upper << 2.9, 1.76, 2.9, -0.07, 2.9, 3.75, 2.9;
  p.velocity_scale = 2.0;
  const EnergyModel model(std::move(p));
  const std::string path = fuzz::ScratchPath("base_energy.h5");
  model.Save(path, "model: gfcs_energy\n", 0);
  return fuzz::ReadFileBytes(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::uint8_t> base = Base();
  fuzz::ByteReader in(data, size);
  const std::string path = fuzz::WriteScratch("energy.h5", base.data(), base.size());
  fuzz::MutateH5(path, &in);
  fuzz::ExpectCleanError(path, [&] {
    const EnergyModel model = EnergyModel::Load(path);
    const Eigen::VectorXf encoding = model.EncodeWorld(World());
    GfcsQuery q;
    q.start.setConstant(0.1);
    q.goal.setConstant(-0.2);
    Eigen::VectorXf context;
    model.Context(q, encoding, &context);
    auto ws = model.MakeWorkspace(2);
    const Eigen::MatrixXf u = Eigen::MatrixXf::Constant(model.command_size(), 2, 0.25f);
    Eigen::VectorXf energy;
    Eigen::MatrixXf grad;
    model.EnergyAndGradient(context, u, &energy, &grad, &ws);
    const JointVector rad = model.Denormalise(JointVector::Constant(0.5));
    fuzz::ExpectFiniteAnswer(encoding.allFinite() && context.allFinite() && energy.allFinite() &&
                                 grad.allFinite() && rad.allFinite(),
                             path, "an energy or its gradient");
  });
  return 0;
}
