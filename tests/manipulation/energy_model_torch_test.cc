// The torch-free energy engine against LibTorch autograd (LibTorch builds only): a random
// torch::nn::Sequential of Linear/ReLU layers, its weights copied into the engine's Mlp, energies
// and dE/du compared for a small net and for the production size (800-800-800-1).
//
// Tolerance: the reference runs in double on the engine's float weights (converted exactly), so
// the difference is the engine's float rounding alone; we require
// |E - E_ref| <= 1e-5 (1 + |E_ref|) and |G - G_ref| <= 1e-5 (1 + max|G_ref|) (absolute + relative
// to the gradient's scale). A float LibTorch run is compared too, with the same bounds.

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <random>

#include "inference/manipulation/energy_model.h"

namespace foresight::manipulation {
namespace {

struct Case {
  int encoding, n;
  std::vector<int> hidden;
  int particles;
};

EnergyModelParts PartsFrom(torch::nn::Sequential& net, int encoding, int n) {
  EnergyModelParts p;
  p.lattice.lower = Eigen::Vector3d::Zero();
  p.lattice.upper = Eigen::Vector3d::Constant(0.3);
  p.lattice.spacing = 0.3;
  p.bps_mean = Eigen::VectorXf::Zero(8);
  p.bps_std = Eigen::VectorXf::Ones(8);
  std::mt19937_64 rng(1);
  std::normal_distribution<float> n01;
  DenseLayer enc;
  enc.weight = Eigen::MatrixXf::NullaryExpr(encoding, 8, [&] { return n01(rng); });
  enc.bias = Eigen::VectorXf::Zero(encoding);
  p.encoder = Mlp({enc});
  std::vector<DenseLayer> layers;
  for (const auto& module : net->children()) {
    auto* linear = module->as<torch::nn::LinearImpl>();
    if (!linear) continue;
    const torch::Tensor w = linear->weight.detach().to(torch::kFloat32).contiguous();
    const torch::Tensor b = linear->bias.detach().to(torch::kFloat32).contiguous();
    DenseLayer l;
    l.weight =
        Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            w.data_ptr<float>(), w.size(0), w.size(1));
    l.bias = Eigen::Map<const Eigen::VectorXf>(b.data_ptr<float>(), b.size(0));
    layers.push_back(std::move(l));
  }
  p.energy = Mlp(std::move(layers));
  p.intermediate_commands = n;
  p.lower = JointVector::Constant(-2);
  p.upper = JointVector::Constant(2);
  return p;
}

void Compare(const Case& c, torch::Dtype reference_dtype) {
  torch::manual_seed(7);
  const int ctx = 21 + c.encoding, D = 7 * c.n;
  torch::nn::Sequential net;
  int in = ctx + D;
  for (int h : c.hidden) {
    net->push_back(torch::nn::Linear(in, h));
    net->push_back(torch::nn::ReLU());
    in = h;
  }
  net->push_back(torch::nn::Linear(in, 1));
  {  // He-scaled weights so that activations, energies and gradients are O(1)
    torch::NoGradGuard guard;
    for (const auto& module : net->children())
      if (auto* linear = module->as<torch::nn::LinearImpl>()) {
        linear->weight.normal_(0.0, std::sqrt(2.0 / linear->weight.size(1)));
        linear->bias.uniform_(-0.1, 0.1);
      }
  }
  const EnergyModelParts parts = PartsFrom(net, c.encoding, c.n);
  // round the torch weights to the engine's floats, then run the reference in reference_dtype
  {
    torch::NoGradGuard guard;
    for (auto& t : net->parameters()) t.copy_(t.to(torch::kFloat32).to(t.dtype()));
  }
  net->to(reference_dtype);
  const EnergyModel model(parts);

  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u11(-1, 1);
  const Eigen::VectorXf context = Eigen::VectorXf::NullaryExpr(ctx, [&] { return u11(rng); });
  const Eigen::MatrixXf u = Eigen::MatrixXf::NullaryExpr(D, c.particles, [&] { return u11(rng); });
  auto ws = model.MakeWorkspace(c.particles);
  Eigen::VectorXf E;
  Eigen::MatrixXf G;
  model.EnergyAndGradient(context, u, &E, &G, &ws);

  // torch: x = [context repeated, u^T] [P x (ctx + D)], rows are particles
  const auto opts = torch::TensorOptions().dtype(torch::kFloat32);
  torch::Tensor tc = torch::from_blob(const_cast<float*>(context.data()), {1, ctx}, opts)
                         .clone()
                         .to(reference_dtype)
                         .expand({c.particles, ctx});
  // u is column-major [D x P]: as row-major it is [P x D]
  torch::Tensor tu = torch::from_blob(const_cast<float*>(u.data()), {c.particles, D}, opts)
                         .clone()
                         .to(reference_dtype)
                         .set_requires_grad(true);
  torch::Tensor e = net->forward(torch::cat({tc, tu}, 1)).squeeze(1);
  e.sum().backward();
  const torch::Tensor e64 = e.detach().to(torch::kFloat64).contiguous();
  const torch::Tensor g64 = tu.grad().to(torch::kFloat64).contiguous();
  double worst_e = 0, worst_g = 0, max_e = 0, max_g = 0;
  for (int p = 0; p < c.particles; ++p) {
    const double er = e64[p].item<double>();
    worst_e = std::max(worst_e, std::abs(E[p] - er) / (1 + std::abs(er)));
    max_e = std::max(max_e, std::abs(er));
    double scale = 0;
    for (int d = 0; d < D; ++d) scale = std::max(scale, std::abs(g64[p][d].item<double>()));
    max_g = std::max(max_g, scale);
    for (int d = 0; d < D; ++d)
      worst_g = std::max(worst_g, std::abs(G(d, p) - g64[p][d].item<double>()) / (1 + scale));
  }
  EXPECT_LE(worst_e, 1e-5) << "energy, hidden " << c.hidden.front();
  EXPECT_LE(worst_g, 1e-5) << "gradient, hidden " << c.hidden.front();
  std::cout << "hidden " << c.hidden.front() << " x " << c.hidden.size() << ", P " << c.particles
            << ", reference " << (reference_dtype == torch::kFloat64 ? "double" : "float")
            << ": max |E| " << max_e << ", max |dE/du| " << max_g
            << "; worst relative energy error " << worst_e << ", gradient " << worst_g << "\n";
  EXPECT_GT(max_e, 0.1);  // a non-trivial comparison
  EXPECT_GT(max_g, 0.1);
}

TEST(EnergyModelTorch, SmallNetMatchesAutograd) {
  for (auto dtype : {torch::kFloat64, torch::kFloat32}) Compare({8, 2, {32, 32, 32}, 17}, dtype);
}

TEST(EnergyModelTorch, ProductionSizeMatchesAutograd) {
  for (auto dtype : {torch::kFloat64, torch::kFloat32})
    Compare({64, 2, {800, 800, 800}, 40}, dtype);
}

}  // namespace
}  // namespace foresight::manipulation
