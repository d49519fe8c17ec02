// The Euclideanizing-Flows engine (torch-free): Jacobian against central differences, the exact
// inverse, the natural-gradient velocity against an independent solve, the repulsor overlay, the
// artifact round trip and bad artifacts.
#include "inference/imitation/eflow.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <random>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using testing::ExpectErrorContains;
using testing::MatricesNear;
using testing::TempDir;

/// Random coupling layers with moderate weights: psi is clearly non-linear but well conditioned.
EFlowModel RandomModel(int d, int layers, int features, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 2 * M_PI);
  std::vector<EFlowCouplingLayer> ls;
  for (int l = 0; l < layers; ++l) {
    EFlowCouplingLayer layer;
    layer.transformed = l % d;
    layer.omega = Eigen::MatrixXd::NullaryExpr(features, d - 1, [&] { return 2 * normal(rng); });
    layer.phase = Eigen::VectorXd::NullaryExpr(features, [&] { return uniform(rng); });
    layer.scale = Eigen::VectorXd::NullaryExpr(features, [&] { return 0.15 * normal(rng); });
    layer.translate = Eigen::VectorXd::NullaryExpr(features, [&] { return 0.3 * normal(rng); });
    ls.push_back(std::move(layer));
  }
  Eigen::VectorXd goal = Eigen::VectorXd::NullaryExpr(d, [&] { return 0.2 * normal(rng); });
  return EFlowModel(d, std::move(ls), goal, 1.7);
}

Eigen::VectorXd RandomPoint(int d, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return Eigen::VectorXd::NullaryExpr(d, [&] { return u(*rng); });
}

Eigen::MatrixXd CentralJacobian(const EFlowModel& m, const Eigen::VectorXd& x, double h) {
  const int d = m.dimension();
  Eigen::MatrixXd j(d, d);
  for (int c = 0; c < d; ++c) {
    Eigen::VectorXd xp = x, xm = x;
    xp[c] += h;
    xm[c] -= h;
    j.col(c) = (m.Forward(xp) - m.Forward(xm)) / (2 * h);
  }
  return j;
}

class EFlowDims : public ::testing::TestWithParam<int> {};

TEST_P(EFlowDims, JacobianMatchesCentralDifferences) {
  const int d = GetParam();
  const EFlowModel m = RandomModel(d, 6, 40, 11 + d);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20; ++i) {
    const Eigen::VectorXd x = RandomPoint(d, &rng);
    Eigen::MatrixXd j;
    const Eigen::VectorXd z = m.Forward(x, &j);
    EXPECT_TRUE(MatricesNear(z, m.Forward(x), 0));  // the Jacobian does not change z
    const Eigen::MatrixXd fd = CentralJacobian(m, x, 1e-5);
    EXPECT_TRUE(MatricesNear(j, fd, 1e-7 * std::max(1.0, fd.cwiseAbs().maxCoeff())));
    // Not the identity: the test exercises the layers.
    EXPECT_GT((j - Eigen::MatrixXd::Identity(d, d)).cwiseAbs().maxCoeff(), 0.05);
    // Coupling layers: det J = prod exp(s) > 0.
    EXPECT_GT(j.determinant(), 0);
  }
}

TEST_P(EFlowDims, InverseIsExact) {
  const int d = GetParam();
  const EFlowModel m = RandomModel(d, 8, 30, 21 + d);
  std::mt19937_64 rng(6);
  for (int i = 0; i < 50; ++i) {
    const Eigen::VectorXd x = 2 * RandomPoint(d, &rng);
    const Eigen::VectorXd z = m.Forward(x);
    EXPECT_GT((z - x).norm(), 1e-3);
    EXPECT_TRUE(MatricesNear(m.Inverse(z), x, 1e-12));
    EXPECT_TRUE(MatricesNear(m.Forward(m.Inverse(x)), x, 1e-12));
  }
}

TEST_P(EFlowDims, VelocityIsTheNaturalGradient) {
  const int d = GetParam();
  const EFlowModel m = RandomModel(d, 6, 40, 31 + d);
  std::mt19937_64 rng(7);
  EXPECT_TRUE(MatricesNear(m.goal_image(), m.Forward(m.goal()), 0));
  for (int i = 0; i < 20; ++i) {
    const Eigen::VectorXd x = RandomPoint(d, &rng);
    const Eigen::VectorXd v = m.Velocity(x);
    // Independent: finite-difference Jacobian and a QR solve.
    const Eigen::VectorXd diff = m.Forward(x) - m.goal_image();
    const Eigen::VectorXd expected =
        -m.speed() * CentralJacobian(m, x, 1e-5).colPivHouseholderQr().solve(diff / diff.norm());
    EXPECT_TRUE(MatricesNear(v, expected, 1e-6));
    // In z the system is the unit-speed attractor: J f = -speed (z - z_e)/||z - z_e||.
    Eigen::MatrixXd j;
    m.Forward(x, &j);
    EXPECT_TRUE(MatricesNear(j * v, -m.speed() * diff / diff.norm(), 1e-12));
  }
  const Eigen::VectorXd at_goal = m.Velocity(m.goal());
  EXPECT_TRUE(at_goal.allFinite());
  EXPECT_EQ(at_goal.norm(), 0);
}

INSTANTIATE_TEST_SUITE_P(Dimensions, EFlowDims, ::testing::Values(2, 3));

TEST(EFlowModel, RepulsorOverlay) {
  const EFlowModel m = RandomModel(2, 4, 20, 41);
  const Eigen::VectorXd x = Eigen::Vector2d(0.3, -0.4);
  const Eigen::VectorXd g = Eigen::Vector2d(2.0, -1.0);
  EXPECT_TRUE(MatricesNear(m.VelocityWithRepulsor(x, g, 0), m.Velocity(x), 0));
  EXPECT_TRUE(MatricesNear(m.VelocityWithRepulsor(x, g, 0.5), m.Velocity(x) - 0.5 * g, 1e-15));
  // The push points down the occupancy gradient.
  EXPECT_LT((m.VelocityWithRepulsor(x, g, 0.5) - m.Velocity(x)).dot(g), 0);
  ExpectErrorContains([&] { m.VelocityWithRepulsor(x, g, -1); }, {"beta", "-1"});
  ExpectErrorContains(
      [&] {
        m.VelocityWithRepulsor(x, Eigen::Vector2d(std::numeric_limits<double>::quiet_NaN(), 0), 1);
      },
      {"grad_p"});
  ExpectErrorContains([&] { m.VelocityWithRepulsor(x, Eigen::Vector3d::Zero(), 1); },
                      {"grad_p", "3"});
}

TEST(EFlowModel, ConstructorRejectsBadLayers) {
  EFlowModel good = RandomModel(2, 3, 5, 51);
  std::vector<EFlowCouplingLayer> layers = good.layers();
  layers[1].transformed = 0;
  ExpectErrorContains([&] { EFlowModel(2, layers, good.goal(), 1, "test model"); },
                      {"test model", "layer 1", "coordinate"});
  layers = good.layers();
  layers[2].scale.resize(4);
  ExpectErrorContains([&] { EFlowModel(2, layers, good.goal(), 1, "test model"); },
                      {"layer 2", "scale"});
  layers = good.layers();
  layers[0].omega(1, 0) = std::numeric_limits<double>::infinity();
  ExpectErrorContains([&] { EFlowModel(2, layers, good.goal(), 1, "test model"); },
                      {"layer 0", "non-finite"});
  ExpectErrorContains([&] { EFlowModel(2, good.layers(), good.goal(), 0, "test model"); },
                      {"speed"});
  ExpectErrorContains([&] { good.Forward(Eigen::Vector3d::Zero()); }, {"Forward", "3"});
}

// Issue 18 (found by fuzzing an edited artifact): finite but huge weights overflow double range for
// some states; the queries then stop with an Error naming the model instead of answering NaN or 0.
TEST(EFlowModel, OverflowingWeightsAreAnErrorNotAnAnswer) {
  const EFlowModel good = RandomModel(2, 3, 5, 52);
  std::vector<EFlowCouplingLayer> layers = good.layers();
  layers[1].scale.setConstant(400.0);  // |s| up to 400 * 5 * sqrt(2 / 5) = 1265 > 709
  bool threw = false;
  const auto check = [&](const Error& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find("huge.h5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("overflows"), std::string::npos) << e.what();
  };
  try {
    // psi(goal) may already overflow (the constructor evaluates it).
    const EFlowModel huge(2, layers, Eigen::Vector2d(0.0, 0.0), 1.0, "huge.h5");
    for (double a = -3; a <= 3 && !threw; a += 0.05) {
      const Eigen::Vector2d x(a, -a);
      try {
        EXPECT_TRUE(huge.Velocity(x).allFinite()) << "non-finite velocity at " << x.transpose();
        Eigen::MatrixXd J;
        const Eigen::VectorXd z = huge.Forward(x, &J);
        EXPECT_TRUE(z.allFinite() && J.allFinite());
      } catch (const Error& e) {
        check(e);
      }
    }
  } catch (const Error& e) {
    check(e);
  }
  EXPECT_TRUE(threw) << "no state overflowed; the test's weights are too small";
}

TEST(EFlowModel, SaveLoadRoundTrip) {
  TempDir dir;
  const std::string path = dir.File("eflow.h5");
  const EFlowModel m = RandomModel(3, 5, 17, 61);
  m.Save(path, "model: diffeo\n", 42);
  const EFlowModel back = EFlowModel::Load(path);
  EXPECT_EQ(back.dimension(), 3);
  EXPECT_EQ(back.num_layers(), 5);
  EXPECT_EQ(back.num_features(), 17);
  EXPECT_EQ(back.speed(), m.speed());
  EXPECT_TRUE(MatricesNear(back.goal(), m.goal(), 0));
  std::mt19937_64 rng(8);
  for (int i = 0; i < 10; ++i) {
    const Eigen::VectorXd x = RandomPoint(3, &rng);
    Eigen::MatrixXd j1, j2;
    EXPECT_TRUE(MatricesNear(back.Forward(x, &j1), m.Forward(x, &j2), 0));
    EXPECT_TRUE(MatricesNear(j1, j2, 0));
    EXPECT_TRUE(MatricesNear(back.Velocity(x), m.Velocity(x), 0));
  }
  const Artifact a = Artifact::Open(path, kEFlowModelType);
  EXPECT_EQ(a.seed(), 42);
  EXPECT_EQ(a.config_yaml(), "model: diffeo\n");
}

/// Overwrites the whole dataset `name` of an existing file with `values` (same size).
void OverwriteDataset(const std::string& path, const std::string& name,
                      const std::vector<double>& values) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Dclose(ds);
  H5Fclose(f);
}

/// Replaces dataset `name` by a float64 dataset of `shape` filled with zeros.
void ReplaceDataset(const std::string& path, const std::string& name,
                    const std::vector<hsize_t>& shape) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  EXPECT_GE(H5Ldelete(f, name.c_str(), H5P_DEFAULT), 0);
  const hid_t space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  const hid_t ds =
      H5Dcreate2(f, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hsize_t n = 1;
  for (hsize_t s : shape) n *= s;
  const std::vector<double> zeros(n, 0.0);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data()), 0);
  H5Dclose(ds);
  H5Sclose(space);
  H5Fclose(f);
}

TEST(EFlowModel, BadArtifactsAreErrors) {
  TempDir dir;
  const EFlowModel m = RandomModel(2, 4, 6, 71);
  const auto fresh = [&](const std::string& name) {
    const std::string p = dir.File(name);
    m.Save(p, "", 1);
    return p;
  };
  ExpectErrorContains([&] { EFlowModel::Load(dir.File("missing.h5")); }, {"missing.h5"});

  const std::string truncated = fresh("truncated.h5");
  testing::Truncate(truncated, 300);
  ExpectErrorContains([&] { EFlowModel::Load(truncated); }, {"truncated.h5"});

  const std::string nan = fresh("nan.h5");
  std::vector<double> scale(4 * 6, 0.1);
  scale[7] = std::numeric_limits<double>::quiet_NaN();
  OverwriteDataset(nan, "/weights/scale", scale);
  ExpectErrorContains([&] { EFlowModel::Load(nan); }, {"nan.h5", "/weights/scale", "non-finite"});

  const std::string shape = fresh("shape.h5");
  ReplaceDataset(shape, "/weights/omega", {4, 5, 1});
  ExpectErrorContains([&] { EFlowModel::Load(shape); },
                      {"shape.h5", "/weights/omega", "4 x 6 x 1"});

  const std::string speed = fresh("speed.h5");
  testing::OverwriteAttr(speed, "/model", "speed", -1.0);
  ExpectErrorContains([&] { EFlowModel::Load(speed); }, {"speed.h5", "speed"});

  const std::string dim = fresh("dim.h5");
  testing::OverwriteAttr(dim, "/model", "dimension", std::int64_t{3});
  ExpectErrorContains([&] { EFlowModel::Load(dim); }, {"dim.h5", "/model/goal"});

  const std::string other = dir.File("other.h5");
  h5::WriteAtomically(other, [](h5::File* f) { Artifact::WriteHeader(f, "hilbert_map", "", 0); });
  ExpectErrorContains([&] { EFlowModel::Load(other); },
                      {"other.h5", "hilbert_map", "diffeo_eflow"});
}

}  // namespace
}  // namespace foresight::imitation
