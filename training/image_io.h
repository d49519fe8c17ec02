#pragma once
/// Pictures written like every other result file: encoded in memory, then written atomically with
/// checked calls (core/file_io.h), so a full disk or a read-only folder is an Error naming the file
/// and its cause, and a half-written picture never replaces a complete one.

#include <string>

namespace cv {
class Mat;
}

namespace foresight {

/// Writes `image` to `path`; the format follows the extension (.png, .jpg, ... as cv::imencode).
void WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace foresight
