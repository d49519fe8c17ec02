#include "training/span/plots.h"

#include <opencv2/imgproc.hpp>
#include <random>

#include "core/error.h"
#include "inference/prediction/span_predictor.h"
#include "training/image_io.h"

namespace foresight::span {

void PlotSamples(const std::string& artifact, const WindowSet& test, const EvalConfig& ec,
                 const std::string& png_path) {
  const Predictor model = Predictor::Load(artifact);
  auto ws = model.MakeWorkspace();
  auto dist = model.MakeDistribution();
  const int panels = std::min(ec.plot_tracks, test.size());
  if (panels == 0) return;
  const int cols = std::min(3, panels), rows = (panels + cols - 1) / cols, size = 320;
  cv::Mat image(rows * size, cols * size, CV_8UC3, cv::Scalar(255, 255, 255));
  const int f = test.predicted, samples = 20;
  Eigen::VectorXd times(f);
  for (int k = 0; k < f; ++k) times[k] = (k + 1) * test.seconds_per_step;
  std::mt19937_64 rng(static_cast<std::uint64_t>(ec.sample_seed));
  Eigen::Matrix<double, Eigen::Dynamic, 2> past(test.observed, 2), mean(f, 2);
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 2>> paths(
      samples, Eigen::Matrix<double, Eigen::Dynamic, 2>(f, 2));
  for (int p = 0; p < panels; ++p) {
    const int n = static_cast<int>(static_cast<long>(p) * test.size() / panels);
    for (int i = 0; i < test.observed; ++i) past.row(i) = test.Past(n, i).transpose();
    model.Predict(past, &ws, &dist);
    for (int k = 0; k < f; ++k) mean.row(k) = dist.MeanPosition(times[k]).transpose();
    for (auto& path : paths) dist.SamplePath(times, &rng, path);
    // Panel bounds: everything drawn, square, with a margin.
    Eigen::Vector2d lo = past.colwise().minCoeff().transpose(),
                    hi = past.colwise().maxCoeff().transpose();
    auto grow = [&](const Eigen::Vector2d& q) { lo = lo.cwiseMin(q), hi = hi.cwiseMax(q); };
    for (int k = 0; k < f; ++k) grow(test.Future(n, k)), grow(mean.row(k).transpose());
    for (const auto& path : paths)
      for (int k = 0; k < f; ++k) grow(path.row(k).transpose());
    const Eigen::Vector2d centre = 0.5 * (lo + hi);
    const double span = std::max((hi - lo).maxCoeff(), 1.0) * 1.1;
    const int ox = (p % cols) * size, oy = (p / cols) * size;
    auto px = [&](const Eigen::Vector2d& q) {
      return cv::Point(ox + static_cast<int>((q.x() - centre.x()) / span * size + size / 2),
                       oy + static_cast<int>(-(q.y() - centre.y()) / span * size + size / 2));
    };
    auto polyline = [&](auto&& point, int count, const cv::Scalar& colour, int thickness) {
      for (int k = 1; k < count; ++k)
        cv::line(image, px(point(k - 1)), px(point(k)), colour, thickness, cv::LINE_AA);
    };
    for (const auto& path : paths)
      polyline(
          [&](int k) {
            return k == 0 ? past.row(test.observed - 1).transpose().eval()
                          : path.row(k - 1).transpose().eval();
          },
          f + 1, cv::Scalar(150, 150, 255), 1);
    polyline([&](int k) { return past.row(k).transpose().eval(); }, test.observed,
             cv::Scalar(200, 80, 0), 2);
    polyline(
        [&](int k) {
          return k == 0 ? past.row(test.observed - 1).transpose().eval() : test.Future(n, k - 1);
        },
        f + 1, cv::Scalar(0, 160, 0), 2);
    polyline(
        [&](int k) {
          return k == 0 ? past.row(test.observed - 1).transpose().eval()
                        : mean.row(k - 1).transpose().eval();
        },
        f + 1, cv::Scalar(0, 0, 160), 2);
    cv::rectangle(image, cv::Rect(ox, oy, size, size), cv::Scalar(200, 200, 200), 1);
    cv::putText(image,
                "window " + std::to_string(n) + "  (" + std::to_string(span).substr(0, 4) + " m)",
                cv::Point(ox + 6, oy + 16), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60),
                1, cv::LINE_AA);
  }
  cv::putText(image, "blue: observed  green: truth  red: samples  dark red: mean",
              cv::Point(6, rows * size - 8), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60),
              1, cv::LINE_AA);
  WriteImage(png_path, image);
}

}  // namespace foresight::span
