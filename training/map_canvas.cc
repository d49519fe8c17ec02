#include "training/map_canvas.h"

namespace foresight {

MapCanvas::MapCanvas(const OccupancyRaster& raster, double pixels_per_metre)
    : extent_(raster.extent), scale_(pixels_per_metre) {
  const int w = std::max(16, static_cast<int>(std::lround((extent_[1] - extent_[0]) * scale_)));
  const int h = std::max(16, static_cast<int>(std::lround((extent_[3] - extent_[2]) * scale_)));
  background_ =
      cv::Mat(h + h % 2, w + w % 2, CV_8UC3, cv::Scalar(255, 255, 255));  // even sizes for codecs
  for (int r = 0; r < background_.rows; ++r)
    for (int c = 0; c < background_.cols; ++c) {
      const double x = extent_[0] + (c + 0.5) / scale_, y = extent_[3] - (r + 0.5) / scale_;
      if (raster.Occupied(x, y)) background_.at<cv::Vec3b>(r, c) = cv::Vec3b(60, 60, 60);
    }
}

cv::Point MapCanvas::Pixel(double x, double y) const {
  return {static_cast<int>(std::lround((x - extent_[0]) * scale_)),
          static_cast<int>(std::lround((extent_[3] - y) * scale_))};
}

}  // namespace foresight
