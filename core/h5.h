#pragma once
/// A small RAII layer over the HDF5 C API: files, groups, attributes and row-major arrays.
/// Every failure throws foresight::Error naming the file and the object.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace foresight::h5 {

/// A row-major n-d array read from a file.
template <typename T>
struct Array {
  std::vector<T> data;
  std::vector<std::size_t> shape;
  std::size_t Size() const { return data.size(); }
};

class File {
 public:
  /// Creates (truncates) `path` for writing.
  static File Create(const std::string& path);
  /// Opens an existing file read-only. A missing, truncated or non-HDF5 file is an Error.
  static File Open(const std::string& path);

  File(File&& other) noexcept;
  File& operator=(File&& other) noexcept;
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  ~File();
  /// Closes the file. A created file lives in memory until then and is written here with checked
  /// system calls: a failure (e.g. a full disk) is an Error naming it. The destructor closes
  /// without checking: writers call Close (or use WriteAtomically).
  void Close();

  const std::string& path() const { return path_; }
  bool Exists(const std::string& object) const;
  /// Names of the members of a group ("/" for the root), sorted.
  std::vector<std::string> List(const std::string& group) const;

  // Attributes on an object ("/" is the root group); a missing object is created as a group.
  void SetAttr(const std::string& object, const std::string& name, const std::string& value);
  void SetAttr(const std::string& object, const std::string& name, std::int64_t value);
  void SetAttr(const std::string& object, const std::string& name, double value);
  bool HasAttr(const std::string& object, const std::string& name) const;
  std::string GetStringAttr(const std::string& object, const std::string& name) const;
  std::int64_t GetIntAttr(const std::string& object, const std::string& name) const;
  double GetDoubleAttr(const std::string& object, const std::string& name) const;

  // Datasets; intermediate groups are created. `shape` is row-major.
  void Write(const std::string& name, const double* data, const std::vector<std::size_t>& shape);
  void Write(const std::string& name, const float* data, const std::vector<std::size_t>& shape);
  void Write(const std::string& name, const std::int64_t* data,
             const std::vector<std::size_t>& shape);
  void Write(const std::string& name, const std::uint8_t* data,
             const std::vector<std::size_t>& shape);
  void WriteString(const std::string& name, const std::string& text);

  Array<double> ReadDouble(const std::string& name) const;
  Array<float> ReadFloat(const std::string& name) const;
  Array<std::int64_t> ReadInt(const std::string& name) const;
  /// Integer dataset read as bytes (values outside 0..255 are converted by HDF5, clipped).
  Array<std::uint8_t> ReadUint8(const std::string& name) const;
  std::string ReadString(const std::string& name) const;

  /// Writes a matrix row-major with shape (rows, cols).
  template <typename Derived>
  void WriteMatrix(const std::string& name, const Eigen::MatrixBase<Derived>& m) {
    using Scalar = typename Derived::Scalar;
    Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = m;
    Write(name, rm.data(),
          {static_cast<std::size_t>(rm.rows()), static_cast<std::size_t>(rm.cols())});
  }
  /// Reads a 2-d (or 1-d, as a column) dataset; checks the shape when expected_* >= 0.
  Eigen::MatrixXd ReadMatrixD(const std::string& name, long expected_rows = -1,
                              long expected_cols = -1) const;
  Eigen::MatrixXf ReadMatrixF(const std::string& name, long expected_rows = -1,
                              long expected_cols = -1) const;

 private:
  File(std::int64_t id, std::string path) : id_(id), path_(std::move(path)) {}
  void CloseQuietly() noexcept;
  void EnsureParentGroups(const std::string& name);
  std::int64_t id_ = -1;
  std::string path_;
  bool writable_ = false;  ///< created by Create: written to path_ on Close
};

/// Writes `path` completely or not at all: `write` fills `path`.tmp, which is closed (checked) and
/// then renamed into place; on any failure the temporary file is removed and the Error propagates.
void WriteAtomically(const std::string& path, const std::function<void(File*)>& write);

}  // namespace foresight::h5
