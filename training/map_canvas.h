#pragma once
/// World <-> image coordinates over an obstacle raster, for the PNGs of map-based methods
/// (navigation paths and videos, constrained-prediction distributions). OpenCV, torch-free.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "datasets/crowd_scenario.h"

namespace foresight {

/// World <-> image of a raster's extent at `pixels_per_metre`.
class MapCanvas {
 public:
  MapCanvas(const OccupancyRaster& raster, double pixels_per_metre);
  cv::Mat Background() const { return background_.clone(); }
  cv::Point Pixel(double x, double y) const;
  int Length(double metres) const {
    return std::max(1, static_cast<int>(std::lround(metres * scale_)));
  }

 private:
  Eigen::Vector4d extent_;
  double scale_;
  cv::Mat background_;
};

}  // namespace foresight
