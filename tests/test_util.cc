#include "tests/test_util.h"

#include <hdf5.h>

#include <fstream>
#include <iterator>

#include "core/h5.h"
#include "inference/engine/artifact.h"
#include "inference/prediction/span_predictor.h"

namespace foresight::testing {

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

Eigen::VectorXd CentralGradient(const std::function<double(const Eigen::VectorXd&)>& f,
                                const Eigen::VectorXd& x, double h) {
  Eigen::VectorXd g(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Eigen::VectorXd a = x, b = x;
    a[i] += h;
    b[i] -= h;
    g[i] = (f(a) - f(b)) / (2 * h);
  }
  return g;
}

::testing::AssertionResult MatricesNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                        double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "shapes differ: " << a.rows() << " x " << a.cols()
                                         << " vs " << b.rows() << " x " << b.cols();
  Eigen::Index r = 0, c = 0;
  const double worst = a.size() ? (a - b).cwiseAbs().maxCoeff(&r, &c) : 0.0;
  if (!(worst <= tol))
    return ::testing::AssertionFailure()
           << "entry (" << r << ", " << c << "): " << a(r, c) << " vs " << b(r, c) << " differ by "
           << worst << " > " << tol;
  return ::testing::AssertionSuccess();
}

namespace {
void OverwriteAttrRaw(const std::string& path, const std::string& object, const std::string& name,
                      hid_t type, const void* value) {
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0) << path;
  const hid_t o = H5Oopen(f, object.c_str(), H5P_DEFAULT);
  ASSERT_GE(o, 0) << object;
  if (H5Aexists(o, name.c_str()) > 0) H5Adelete(o, name.c_str());
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(o, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(H5Awrite(a, type, value), 0);
  H5Aclose(a);
  H5Sclose(space);
  H5Oclose(o);
  EXPECT_GE(H5Fclose(f), 0);
}
}  // namespace

void OverwriteAttr(const std::string& path, const std::string& object, const std::string& name,
                   std::int64_t value) {
  OverwriteAttrRaw(path, object, name, H5T_NATIVE_INT64, &value);
}

void OverwriteAttr(const std::string& path, const std::string& object, const std::string& name,
                   double value) {
  OverwriteAttrRaw(path, object, name, H5T_NATIVE_DOUBLE, &value);
}

void Truncate(const std::string& path, std::size_t bytes) {
  std::filesystem::resize_file(path, bytes);
}

std::string SharedDataDir() {
  const char* src = std::getenv("FORESIGHT_SOURCE_DIR");
  const std::filesystem::path root = src ? src : ".";
  const auto dir = root / ".." / "shared" / "data";
  return std::filesystem::exists(dir) ? std::filesystem::canonical(dir).string() : "";
}

void WriteRandomSpanArtifact(const std::string& path, const RandomSpanSpec& s) {
  HeadLayout layout{s.basis, s.components, s.u_param};
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<float> n01;
  span::PredictorWeights w;
  w.observed = s.observed;
  w.predicted = s.predicted;
  w.seconds_per_step = s.seconds_per_step;
  w.rotate_to_heading = s.rotate;
  w.residual_to_constant_velocity = s.residual_cv;
  w.layout = layout;
  w.basis_centres = Eigen::VectorXd::LinSpaced(s.basis, 0.0, s.predicted * s.seconds_per_step);
  w.basis_gamma = 1.0;
  w.input_mean = Eigen::VectorXd::Zero(2 * s.observed);
  w.input_std = Eigen::VectorXd::Constant(2 * s.observed, 2.0);
  std::vector<int> widths{2 * s.observed};
  widths.insert(widths.end(), s.hidden.begin(), s.hidden.end());
  widths.push_back(layout.Total());
  std::vector<DenseLayer> layers;
  for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
    const std::string name = i + 2 == widths.size() ? "head" : "mlp." + std::to_string(2 * i);
    w.layer_names.push_back(name);
    DenseLayer l;
    l.weight.resize(widths[i + 1], widths[i]);
    for (Eigen::Index k = 0; k < l.weight.size(); ++k)
      l.weight.data()[k] = n01(rng) / std::sqrt(static_cast<float>(widths[i]));
    if (name == "head") l.weight *= 0.1f;
    l.bias.resize(widths[i + 1]);
    for (Eigen::Index k = 0; k < l.bias.size(); ++k) l.bias[k] = 0.1f * n01(rng);
    layers.push_back(std::move(l));
  }
  w.mlp = Mlp(std::move(layers));
  span::Predictor::Save(path, w, "model: span_predictor\n", 0);
}

}  // namespace foresight::testing
