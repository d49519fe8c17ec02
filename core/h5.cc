#include "core/h5.h"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>

#include "core/error.h"
#include "core/file_io.h"

namespace foresight::h5 {
namespace {

static_assert(sizeof(hid_t) == sizeof(std::int64_t), "hid_t is expected to be 64-bit");

// Silence the HDF5 error stack printer once; errors become exceptions with our own message.
void QuietHdf5() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

/// Closes an HDF5 handle with the matching close function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() {
    if (id_ >= 0) closer_(id_);
  }
  Handle(Handle&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = -1; }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  Closer closer_;
};

template <typename T>
hid_t MemType();
template <>
hid_t MemType<double>() {
  return H5T_NATIVE_DOUBLE;
}
template <>
hid_t MemType<float>() {
  return H5T_NATIVE_FLOAT;
}
template <>
hid_t MemType<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t MemType<std::uint8_t>() {
  return H5T_NATIVE_UINT8;
}

std::string ObjectName(const std::string& object) { return object.empty() ? "/" : object; }

/// A creation property list of class `cls` (groups, datasets) without modification times, so
/// the same content makes the same file, bit for bit (a resumed run's artifact is compared so).
Handle UntimedCreation(hid_t cls) {
  Handle list(H5Pcreate(cls), H5Pclose);
  if (list.ok()) H5Pset_obj_track_times(list.get(), 0);
  return list;
}

}  // namespace

File File::Create(const std::string& path) {
  QuietHdf5();
  // The file is built in memory (HDF5's core driver without a backing store) and written by Close
  // with checked POSIX calls: HDF5 then never meets a failing disk, whose errors it cannot always
  // recover from (a failed close left a file that crashed the library's shutdown).
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  FS_THROW_UNLESS(fapl.ok() && H5Pset_fapl_core(fapl.get(), 1 << 20, 0) >= 0, path,
                  ": cannot set up an in-memory HDF5 file");
  hid_t id = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get());
  FS_THROW_UNLESS(id >= 0, path, ": cannot create HDF5 file");
  File f(id, path);
  f.writable_ = true;
  return f;
}

File File::Open(const std::string& path) {
  QuietHdf5();
  FILE* probe = std::fopen(path.c_str(), "rb");
  FS_THROW_UNLESS(probe != nullptr, path, ": file not found or not readable");
  std::fclose(probe);
  FS_THROW_UNLESS(H5Fis_hdf5(path.c_str()) > 0, path,
                  ": not a readable HDF5 file (truncated or of another format)");
  hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  FS_THROW_UNLESS(id >= 0, path, ": not a readable HDF5 file (truncated or of another format)");
  return File(id, path);
}

File::File(File&& other) noexcept
    : id_(other.id_), path_(std::move(other.path_)), writable_(other.writable_) {
  other.id_ = -1;
}

File& File::operator=(File&& other) noexcept {
  if (this != &other) {
    CloseQuietly();
    id_ = other.id_;
    path_ = std::move(other.path_);
    writable_ = other.writable_;
    other.id_ = -1;
  }
  return *this;
}

File::~File() { CloseQuietly(); }

void File::CloseQuietly() noexcept {
  try {
    Close();
  } catch (...) {
    // Unchecked, as a destructor must be: writers that need to know call Close().
  }
}

void File::Close() {
  if (id_ < 0) return;
  const hid_t id = id_;
  id_ = -1;
  if (!writable_) {
    H5Fclose(id);
    return;
  }
  bool ok = H5Fflush(id, H5F_SCOPE_GLOBAL) >= 0;
  const ssize_t size = ok ? H5Fget_file_image(id, nullptr, 0) : -1;
  std::vector<char> image(size > 0 ? static_cast<std::size_t>(size) : 0);
  ok = ok && size > 0 && H5Fget_file_image(id, image.data(), image.size()) == size;
  ok = H5Fclose(id) >= 0 && ok;
  FS_THROW_UNLESS(ok, path_, ": cannot serialise the HDF5 file");
  WriteFileBytes(path_, image.data(), image.size());
}

void WriteAtomically(const std::string& path, const std::function<void(File*)>& write) {
  WriteThroughTemporary(path, [&](const std::string& tmp) {
    File f = File::Create(tmp);
    write(&f);
    f.Close();
  });
}

bool File::Exists(const std::string& object) const {
  if (object == "/" || object.empty()) return true;
  // Check each prefix: H5Lexists fails on a missing intermediate group.
  std::size_t pos = 0;
  while (true) {
    pos = object.find('/', pos + 1);
    const std::string prefix = object.substr(0, pos);
    if (!prefix.empty() && prefix != "/" && H5Lexists(id_, prefix.c_str(), H5P_DEFAULT) <= 0)
      return false;
    if (pos == std::string::npos) return true;
  }
}

std::vector<std::string> File::List(const std::string& group) const {
  Handle g(H5Gopen2(id_, ObjectName(group).c_str(), H5P_DEFAULT), H5Gclose);
  FS_THROW_UNLESS(g.ok(), path_, ": no group '", group, "'");
  H5G_info_t info;
  FS_THROW_UNLESS(H5Gget_info(g.get(), &info) >= 0, path_, ": cannot read group '", group, "'");
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    ssize_t n =
        H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (n < 0) continue;
    std::string name(static_cast<std::size_t>(n), '\0');
    H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size() + 1,
                       H5P_DEFAULT);
    names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

namespace {
void EnsureGroup(hid_t file, const std::string& path, const std::string& group) {
  if (group.empty() || group == "/") return;
  std::size_t pos = 0;
  while (true) {
    pos = group.find('/', pos + 1);
    const std::string prefix = group.substr(0, pos);
    if (!prefix.empty() && prefix != "/" && H5Lexists(file, prefix.c_str(), H5P_DEFAULT) <= 0) {
      Handle g(H5Gcreate2(file, prefix.c_str(), H5P_DEFAULT,
                          UntimedCreation(H5P_GROUP_CREATE).get(), H5P_DEFAULT),
               H5Gclose);
      FS_THROW_UNLESS(g.ok(), path, ": cannot create group '", prefix, "'");
    }
    if (pos == std::string::npos) return;
  }
}

void WriteAttrRaw(hid_t file, const std::string& path, const std::string& object,
                  const std::string& name, hid_t type, const void* data) {
  EnsureGroup(file, path, ObjectName(object));
  Handle obj(H5Oopen(file, ObjectName(object).c_str(), H5P_DEFAULT), H5Oclose);
  FS_THROW_UNLESS(obj.ok(), path, ": no object '", object, "' for attribute '", name, "'");
  if (H5Aexists(obj.get(), name.c_str()) > 0) H5Adelete(obj.get(), name.c_str());
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(H5Acreate2(obj.get(), name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              H5Aclose);
  FS_THROW_UNLESS(attr.ok() && H5Awrite(attr.get(), type, data) >= 0, path,
                  ": cannot write attribute '", name, "' on '", object, "'");
}

Handle OpenAttr(hid_t file, const std::string& path, const std::string& object,
                const std::string& name) {
  Handle obj(H5Oopen(file, ObjectName(object).c_str(), H5P_DEFAULT), H5Oclose);
  FS_THROW_UNLESS(obj.ok(), path, ": no object '", object, "'");
  FS_THROW_UNLESS(H5Aexists(obj.get(), name.c_str()) > 0, path, ": missing attribute '", name,
                  "' on '", object, "'");
  hid_t a = H5Aopen(obj.get(), name.c_str(), H5P_DEFAULT);
  FS_THROW_UNLESS(a >= 0, path, ": cannot open attribute '", name, "' on '", object, "'");
  Handle attr(a, H5Aclose);
  // The scalar readers have room for one element: an array attribute is an error, not an overflow.
  Handle space(H5Aget_space(attr.get()), H5Sclose);
  const hssize_t count = space.ok() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  FS_THROW_UNLESS(count == 1, path, ": attribute '", name, "' on '", object, "' holds ", count,
                  " elements, expected a single value");
  return attr;
}
}  // namespace

void File::SetAttr(const std::string& object, const std::string& name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  std::string padded = value.empty() ? std::string(1, '\0') : value;
  WriteAttrRaw(id_, path_, object, name, type.get(), padded.data());
}

void File::SetAttr(const std::string& object, const std::string& name, std::int64_t value) {
  WriteAttrRaw(id_, path_, object, name, H5T_NATIVE_INT64, &value);
}

void File::SetAttr(const std::string& object, const std::string& name, double value) {
  WriteAttrRaw(id_, path_, object, name, H5T_NATIVE_DOUBLE, &value);
}

bool File::HasAttr(const std::string& object, const std::string& name) const {
  if (!Exists(object)) return false;
  Handle obj(H5Oopen(id_, ObjectName(object).c_str(), H5P_DEFAULT), H5Oclose);
  return obj.ok() && H5Aexists(obj.get(), name.c_str()) > 0;
}

std::string File::GetStringAttr(const std::string& object, const std::string& name) const {
  Handle attr = OpenAttr(id_, path_, object, name);
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  FS_THROW_UNLESS(H5Tget_class(type.get()) == H5T_STRING, path_, ": attribute '", name, "' on '",
                  object, "' is not a string");
  FS_THROW_UNLESS(H5Tis_variable_str(type.get()) <= 0, path_, ": attribute '", name,
                  "' is a variable-length string (unsupported)");
  std::size_t size = H5Tget_size(type.get());
  std::string out(size, '\0');
  FS_THROW_UNLESS(H5Aread(attr.get(), type.get(), out.data()) >= 0, path_,
                  ": cannot read attribute '", name, "'");
  out.resize(std::strlen(out.c_str()));
  // Loaders echo these values in one-line errors: an edited file must not smuggle in line breaks.
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto c = static_cast<unsigned char>(out[i]);
    FS_THROW_UNLESS((c >= 0x20 || c == '\t') && c != 0x7f, path_, ": attribute '", name, "' on '",
                    object, "' holds control character ", static_cast<int>(c), " at position ", i,
                    "; expected printable text");
  }
  return out;
}

std::int64_t File::GetIntAttr(const std::string& object, const std::string& name) const {
  Handle attr = OpenAttr(id_, path_, object, name);
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  FS_THROW_UNLESS(H5Tget_class(type.get()) == H5T_INTEGER, path_, ": attribute '", name, "' on '",
                  object, "' is not an integer");
  std::int64_t v = 0;
  FS_THROW_UNLESS(H5Aread(attr.get(), H5T_NATIVE_INT64, &v) >= 0, path_,
                  ": cannot read attribute '", name, "'");
  return v;
}

double File::GetDoubleAttr(const std::string& object, const std::string& name) const {
  Handle attr = OpenAttr(id_, path_, object, name);
  Handle type(H5Aget_type(attr.get()), H5Tclose);
  FS_THROW_UNLESS(H5Tget_class(type.get()) == H5T_FLOAT || H5Tget_class(type.get()) == H5T_INTEGER,
                  path_, ": attribute '", name, "' on '", object, "' is not a number");
  double v = 0;
  FS_THROW_UNLESS(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v) >= 0, path_,
                  ": cannot read attribute '", name, "'");
  return v;
}

void File::EnsureParentGroups(const std::string& name) {
  std::size_t pos = 0;
  while ((pos = name.find('/', pos + 1)) != std::string::npos) {
    const std::string group = name.substr(0, pos);
    if (group.empty() || group == "/") continue;
    if (H5Lexists(id_, group.c_str(), H5P_DEFAULT) > 0) continue;
    Handle g(H5Gcreate2(id_, group.c_str(), H5P_DEFAULT, UntimedCreation(H5P_GROUP_CREATE).get(),
                        H5P_DEFAULT),
             H5Gclose);
    FS_THROW_UNLESS(g.ok(), path_, ": cannot create group '", group, "'");
  }
}

namespace {
template <typename T>
void WriteRaw(hid_t file, const std::string& path, const std::string& name, const T* data,
              const std::vector<std::size_t>& shape) {
  std::vector<hsize_t> dims(shape.begin(), shape.end());
  Handle space(dims.empty() ? H5Screate(H5S_SCALAR)
                            : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
               H5Sclose);
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  Handle ds(H5Dcreate2(file, name.c_str(), MemType<T>(), space.get(), H5P_DEFAULT,
                       UntimedCreation(H5P_DATASET_CREATE).get(), H5P_DEFAULT),
            H5Dclose);
  FS_THROW_UNLESS(ds.ok(), path, ": cannot create dataset '", name, "'");
  std::size_t count = 1;
  for (auto d : shape) count *= d;
  if (count > 0)
    FS_THROW_UNLESS(H5Dwrite(ds.get(), MemType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0,
                    path, ": cannot write dataset '", name, "'");
}

template <typename T>
Array<T> ReadRaw(hid_t file, const std::string& path, const std::string& name,
                 H5T_class_t expected_class) {
  FS_THROW_UNLESS(H5Lexists(file, name.c_str(), H5P_DEFAULT) > 0 || name == "/", path,
                  ": missing dataset '", name, "'");
  Handle ds(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  FS_THROW_UNLESS(ds.ok(), path, ": missing dataset '", name, "'");
  Handle type(H5Dget_type(ds.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.get());
  FS_THROW_UNLESS(cls == expected_class || (expected_class == H5T_FLOAT && cls == H5T_INTEGER),
                  path, ": dataset '", name, "' has the wrong element type");
  Handle space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  FS_THROW_UNLESS(rank >= 0, path, ": dataset '", name, "' has an unreadable shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  Array<T> out;
  std::size_t count = 1;
  for (auto d : dims) {
    out.shape.push_back(static_cast<std::size_t>(d));
    count *= static_cast<std::size_t>(d);
  }
  out.data.resize(count);
  if (count > 0)
    FS_THROW_UNLESS(
        H5Dread(ds.get(), MemType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data.data()) >= 0, path,
        ": cannot read dataset '", name, "' (file truncated or corrupt?)");
  return out;
}

template <typename Matrix, typename T>
Matrix ToMatrix(const Array<T>& a, const std::string& path, const std::string& name, long rows,
                long cols) {
  FS_THROW_UNLESS(a.shape.size() <= 2, path, ": dataset '", name, "' has rank ", a.shape.size(),
                  ", expected a matrix");
  const long r = a.shape.empty() ? 1 : static_cast<long>(a.shape[0]);
  const long c = a.shape.size() < 2 ? 1 : static_cast<long>(a.shape[1]);
  FS_THROW_UNLESS((rows < 0 || rows == r) && (cols < 0 || cols == c), path, ": dataset '", name,
                  "' has shape ", r, "x", c, ", expected ", rows, "x", cols);
  Matrix m(r, c);
  for (long i = 0; i < r; ++i)
    for (long j = 0; j < c; ++j) m(i, j) = a.data[static_cast<std::size_t>(i * c + j)];
  return m;
}
}  // namespace

void File::Write(const std::string& name, const double* data,
                 const std::vector<std::size_t>& shape) {
  EnsureParentGroups(name);
  WriteRaw(id_, path_, name, data, shape);
}
void File::Write(const std::string& name, const float* data,
                 const std::vector<std::size_t>& shape) {
  EnsureParentGroups(name);
  WriteRaw(id_, path_, name, data, shape);
}
void File::Write(const std::string& name, const std::int64_t* data,
                 const std::vector<std::size_t>& shape) {
  EnsureParentGroups(name);
  WriteRaw(id_, path_, name, data, shape);
}

void File::Write(const std::string& name, const std::uint8_t* data,
                 const std::vector<std::size_t>& shape) {
  EnsureParentGroups(name);
  WriteRaw(id_, path_, name, data, shape);
}

void File::WriteString(const std::string& name, const std::string& text) {
  EnsureParentGroups(name);
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(text.size(), 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  if (H5Lexists(id_, name.c_str(), H5P_DEFAULT) > 0) H5Ldelete(id_, name.c_str(), H5P_DEFAULT);
  Handle ds(H5Dcreate2(id_, name.c_str(), type.get(), space.get(), H5P_DEFAULT,
                       UntimedCreation(H5P_DATASET_CREATE).get(), H5P_DEFAULT),
            H5Dclose);
  std::string padded = text.empty() ? std::string(1, '\0') : text;
  FS_THROW_UNLESS(
      ds.ok() && H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, padded.data()) >= 0,
      path_, ": cannot write string dataset '", name, "'");
}

std::string File::ReadString(const std::string& name) const {
  FS_THROW_UNLESS(Exists(name), path_, ": missing dataset '", name, "'");
  Handle ds(H5Dopen2(id_, name.c_str(), H5P_DEFAULT), H5Dclose);
  FS_THROW_UNLESS(ds.ok(), path_, ": missing dataset '", name, "'");
  Handle type(H5Dget_type(ds.get()), H5Tclose);
  FS_THROW_UNLESS(H5Tget_class(type.get()) == H5T_STRING && H5Tis_variable_str(type.get()) <= 0,
                  path_, ": dataset '", name, "' is not a fixed-length string");
  Handle space(H5Dget_space(ds.get()), H5Sclose);
  const hssize_t count = space.ok() ? H5Sget_simple_extent_npoints(space.get()) : -1;
  FS_THROW_UNLESS(count == 1, path_, ": string dataset '", name, "' holds ", count,
                  " elements, expected a single string");
  std::string out(H5Tget_size(type.get()), '\0');
  FS_THROW_UNLESS(H5Dread(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0,
                  path_, ": cannot read dataset '", name, "' (file truncated or corrupt?)");
  out.resize(std::strlen(out.c_str()));
  return out;
}

Array<double> File::ReadDouble(const std::string& name) const {
  FS_THROW_UNLESS(Exists(name), path_, ": missing dataset '", name, "'");
  return ReadRaw<double>(id_, path_, name, H5T_FLOAT);
}
Array<float> File::ReadFloat(const std::string& name) const {
  FS_THROW_UNLESS(Exists(name), path_, ": missing dataset '", name, "'");
  return ReadRaw<float>(id_, path_, name, H5T_FLOAT);
}
Array<std::uint8_t> File::ReadUint8(const std::string& name) const {
  FS_THROW_UNLESS(Exists(name), path_, ": missing dataset '", name, "'");
  return ReadRaw<std::uint8_t>(id_, path_, name, H5T_INTEGER);
}
Array<std::int64_t> File::ReadInt(const std::string& name) const {
  FS_THROW_UNLESS(Exists(name), path_, ": missing dataset '", name, "'");
  return ReadRaw<std::int64_t>(id_, path_, name, H5T_INTEGER);
}

Eigen::MatrixXd File::ReadMatrixD(const std::string& name, long rows, long cols) const {
  return ToMatrix<Eigen::MatrixXd>(ReadDouble(name), path_, name, rows, cols);
}
Eigen::MatrixXf File::ReadMatrixF(const std::string& name, long rows, long cols) const {
  return ToMatrix<Eigen::MatrixXf>(ReadFloat(name), path_, name, rows, cols);
}

}  // namespace foresight::h5
