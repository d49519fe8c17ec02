// The diffeo_template artifact: save/load round trips to the bit, and every kind of bad file
// (truncated, foreign, NaN, wrong shape, out of range, non-invertible) is an Error naming it.

#include "inference/imitation/template_artifact.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <random>

#include "inference/mapping/hinge_map.h"
#include "tests/occupancy_test_util.h"
#include "tests/test_util.h"

namespace foresight::imitation {
namespace {

using testing::ExpectErrorContains;

template <int D>
ImitationSystem<D> RandomSystem(double scale, std::uint64_t seed,
                                FlowSettings<D> settings = {1.0, 10}) {
  RbfGridSpec<D> s;
  s.lower = Vec<D>::Constant(-0.6);
  s.counts.fill(D == 2 ? 13 : 7);
  s.spacing = D == 2 ? 0.1 : 0.2;
  s.gamma = D == 2 ? 120 : 40;
  s.cutoff_radius = D == 2 ? 0.4 : 0.7;
  const RbfGrid<D> grid(s);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd w(settings.segments * grid.size(), D);
  for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = scale * n01(rng);
  return ImitationSystem<D>(RbfFlow<D>(grid, w, settings), Vec<D>::Constant(0.1), 0.8);
}

template <int D>
TemplateNormalisation Normalisation() {
  TemplateNormalisation n;
  n.offset = Eigen::VectorXd::LinSpaced(D, -3.5, 12.25);
  n.scale = 0.0125;
  return n;
}

template <int D>
void CheckRoundTrip(int segments = 1) {
  testing::TempDir dir;
  const std::string path = dir.File("template.h5");
  const ImitationSystem<D> system =
      RandomSystem<D>(D == 2 ? 0.05 : 0.03, 1, FlowSettings<D>{1.0, 10, segments});
  SaveTemplate<D>(path, system, Normalisation<D>(), "kind: imitation\n", 42);
  EXPECT_EQ(TemplateDimension(path), D);
  const TemplateArtifact<D> loaded = LoadTemplate<D>(path);
  EXPECT_EQ(loaded.config_yaml, "kind: imitation\n");
  EXPECT_EQ(loaded.seed, 42);
  EXPECT_EQ(loaded.normalisation.scale, 0.0125);
  EXPECT_TRUE(testing::MatricesNear(loaded.normalisation.offset, Normalisation<D>().offset, 0));
  EXPECT_EQ(loaded.system.speed(), system.speed());
  EXPECT_EQ(loaded.system.flow().settings().steps, 10);
  EXPECT_EQ(loaded.system.flow().settings().segments, segments);
  EXPECT_TRUE(testing::MatricesNear(loaded.system.goal(), system.goal(), 0));
  FlowWorkspace<D> a = system.flow().MakeWorkspace(), b = loaded.system.flow().MakeWorkspace();
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  for (int n = 0; n < 50; ++n) {
    Vec<D> x;
    for (int i = 0; i < D; ++i) x[i] = u(rng);
    const Vec<D> va = system.Velocity(x, &a), vb = loaded.system.Velocity(x, &b);
    for (int i = 0; i < D; ++i) EXPECT_EQ(va[i], vb[i]) << "bit-for-bit at " << x.transpose();
  }
  // The wrong dimension is refused.
  if constexpr (D == 2) {
    ExpectErrorContains([&] { LoadTemplate<3>(path); }, {path, "dimension", "2"});
  }
}

TEST(TemplateArtifact, RoundTripIsBitForBit2D) { CheckRoundTrip<2>(); }
TEST(TemplateArtifact, RoundTripIsBitForBit3D) { CheckRoundTrip<3>(); }
TEST(TemplateArtifact, RoundTripWithSegmentsIsBitForBit2D) { CheckRoundTrip<2>(4); }
TEST(TemplateArtifact, RoundTripWithSegmentsIsBitForBit3D) { CheckRoundTrip<3>(3); }

// Replaces dataset `name` by a double array of `shape` (HDF5 C API: independent of core/h5).
void ReplaceDataset(const std::string& path, const std::string& name,
                    const std::vector<double>& data, const std::vector<hsize_t>& shape) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, name.c_str(), H5P_DEFAULT), 0) << name;
  const hid_t space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  const hid_t ds =
      H5Dcreate2(f, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), 0);
  H5Dclose(ds);
  H5Sclose(space);
  EXPECT_GE(H5Fclose(f), 0);
}

class BadTemplate : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = dir_.File("template.h5");
    system_ = RandomSystem<2>(0.05, 3);
    SaveTemplate<2>(path_, system_, Normalisation<2>(), "", 1);
    ASSERT_NO_THROW(LoadTemplate<2>(path_));
  }
  std::vector<double> Weights() const {
    const Eigen::MatrixXd& w = system_.flow().weights();
    std::vector<double> rm;
    for (Eigen::Index i = 0; i < w.rows(); ++i)
      for (Eigen::Index j = 0; j < w.cols(); ++j) rm.push_back(w(i, j));
    return rm;
  }
  testing::TempDir dir_;
  std::string path_;
  ImitationSystem<2> system_;
};

TEST_F(BadTemplate, Truncated) {
  testing::Truncate(path_, 600);
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_});
  ExpectErrorContains([&] { TemplateDimension(path_); }, {path_});
}

TEST_F(BadTemplate, WrongModelType) {
  HingeGridConfig c;
  c.x_min = 0;
  c.x_max = 2;
  c.y_min = 0;
  c.y_max = 2;
  testing::RandomHingeMap(occupancy::HingeMapKind::kHilbert, HingeGrid(c), 1).Save(path_, "", 1);
  ExpectErrorContains([&] { LoadTemplate<2>(path_); },
                      {path_, "occupancy.hilbert", "diffeo_template"});
}

TEST_F(BadTemplate, NanWeight) {
  std::vector<double> w = Weights();
  w[17] = std::nan("");
  ReplaceDataset(path_, "/model/weights", w, {169, 2});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "/model/weights", "not finite"});
}

TEST_F(BadTemplate, ShapeMismatch) {
  std::vector<double> w = Weights();
  w.resize(w.size() - 2);
  ReplaceDataset(path_, "/model/weights", w, {168, 2});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "/model/weights", "168", "169"});
  ReplaceDataset(path_, "/model/weights", Weights(), {169, 2});
  ReplaceDataset(path_, "/model/goal", {0.1, 0.1, 0.1}, {3});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "/model/goal", "3"});
  ReplaceDataset(path_, "/model/goal", {0.1, 0.1}, {2});
  ReplaceDataset(path_, "/normalisation/offset", {std::nan(""), 0.0}, {2});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "/normalisation/offset", "finite"});
}

TEST_F(BadTemplate, OutOfRangeAttributes) {
  testing::OverwriteAttr(path_, "/model", "steps", std::int64_t{0});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "steps", "0"});
  testing::OverwriteAttr(path_, "/model", "steps", std::int64_t{10});
  testing::OverwriteAttr(path_, "/model", "spacing", -0.1);
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "spacing"});
  testing::OverwriteAttr(path_, "/model", "spacing", 0.1);
  testing::OverwriteAttr(path_, "/normalisation", "scale", std::nan(""));
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "scale"});
  testing::OverwriteAttr(path_, "/normalisation", "scale", 1.0);
  testing::OverwriteAttr(path_, "/model", "dimension", std::int64_t{4});
  ExpectErrorContains([&] { TemplateDimension(path_); }, {path_, "dimension", "4"});
}

// Templates written before segments existed have no /model/segments: one stationary field.
TEST_F(BadTemplate, SegmentsAttributeIsOptionalAndChecked) {
  {
    const hid_t f = H5Fopen(path_.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    EXPECT_GE(H5Adelete_by_name(f, "/model", "segments", H5P_DEFAULT), 0);
    EXPECT_GE(H5Fclose(f), 0);
  }
  EXPECT_EQ(LoadTemplate<2>(path_).system.flow().settings().segments, 1);
  testing::OverwriteAttr(path_, "/model", "segments", std::int64_t{11});
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "segments", "11"});
  testing::OverwriteAttr(path_, "/model", "segments", std::int64_t{2});  // 169 rows, 338 needed
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "/model/weights", "338"});
}

TEST_F(BadTemplate, NonInvertibleFlowIsRefused) {
  SaveTemplate<2>(path_, RandomSystem<2>(2.0, 4, {3.0, 2}), Normalisation<2>(), "", 1);
  ExpectErrorContains([&] { LoadTemplate<2>(path_); }, {path_, "not invertible", "determinant"});
}

TEST(TemplateArtifact, SaveChecksTheNormalisation) {
  testing::TempDir dir;
  TemplateNormalisation n = Normalisation<2>();
  n.scale = 0;
  ExpectErrorContains(
      [&] { SaveTemplate<2>(dir.File("t.h5"), RandomSystem<2>(0.05, 1), n, "", 1); }, {"scale"});
  n = Normalisation<3>();
  ExpectErrorContains(
      [&] { SaveTemplate<2>(dir.File("t.h5"), RandomSystem<2>(0.05, 1), n, "", 1); },
      {"offset", "3"});
}

}  // namespace
}  // namespace foresight::imitation
