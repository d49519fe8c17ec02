#include "training/image_io.h"

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "core/error.h"
#include "core/file_io.h"

namespace foresight {

void WriteImage(const std::string& path, const cv::Mat& image) {
  FS_THROW_UNLESS(!image.empty(), path, ": cannot write an empty picture");
  const std::string ext = std::filesystem::path(path).extension().string();
  FS_THROW_UNLESS(!ext.empty(), path, ": the file name needs an extension (.png) for its format");
  std::vector<unsigned char> bytes;
  bool encoded = false;
  try {
    encoded = cv::imencode(ext, image, bytes);
  } catch (const cv::Exception& e) {
    Fail(path, ": cannot encode the picture as ", ext, " (", e.what(), ")");
  }
  FS_THROW_UNLESS(encoded, path, ": cannot encode the picture as ", ext);
  WriteFileAtomically(path, std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace foresight
