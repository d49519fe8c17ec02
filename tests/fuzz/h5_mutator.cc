#include "tests/fuzz/h5_mutator.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace foresight::fuzz {
namespace {

/// FORESIGHT_FUZZ_VERBOSE=1 prints each edit (to see what an input that broke a target does).
void Note(const std::string& edit, const std::string& object, const std::string& detail = "") {
  static const bool verbose = std::getenv("FORESIGHT_FUZZ_VERBOSE") != nullptr;
  if (verbose)
    std::fprintf(stderr, "h5 edit: %s %s %s\n", edit.c_str(), object.c_str(), detail.c_str());
}

/// Closes an HDF5 id with its close function at scope exit.
class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Id() {
    if (id_ >= 0) closer_(id_);
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  Closer closer_;
};

struct Attr {
  std::string object, name;
  H5T_class_t cls;
};

struct Inventory {
  std::vector<std::string> objects;   ///< "/" and every group and dataset
  std::vector<std::string> datasets;  ///< every dataset
  std::vector<Attr> attrs;
};

herr_t CollectLink(hid_t, const char* name, const H5L_info_t* info, void* data) {
  if (info->type != H5L_TYPE_HARD) return 0;
  static_cast<std::vector<std::string>*>(data)->push_back(std::string("/") + name);
  return 0;
}

herr_t CollectAttr(hid_t, const char* name, const H5A_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->push_back(name);
  return 0;
}

Inventory Collect(hid_t file) {
  Inventory inv;
  std::vector<std::string> links;
  H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, CollectLink, &links);
  inv.objects.push_back("/");
  for (const auto& l : links) {
    Id obj(H5Oopen(file, l.c_str(), H5P_DEFAULT), H5Oclose);
    if (!obj.ok()) continue;
    const H5I_type_t type = H5Iget_type(obj.get());
    if (type == H5I_DATASET) inv.datasets.push_back(l);
    if (type == H5I_DATASET || type == H5I_GROUP) inv.objects.push_back(l);
  }
  for (const auto& o : inv.objects) {
    Id obj(H5Oopen(file, o.c_str(), H5P_DEFAULT), H5Oclose);
    if (!obj.ok()) continue;
    std::vector<std::string> names;
    hsize_t idx = 0;
    H5Aiterate2(obj.get(), H5_INDEX_NAME, H5_ITER_INC, &idx, CollectAttr, &names);
    for (const auto& n : names) {
      Id attr(H5Aopen(obj.get(), n.c_str(), H5P_DEFAULT), H5Aclose);
      if (!attr.ok()) continue;
      Id type(H5Aget_type(attr.get()), H5Tclose);
      inv.attrs.push_back({o, n, H5Tget_class(type.get())});
    }
  }
  return inv;
}

/// A double as int64 with saturation (NaN -> 0): what a user can store in an integer attribute.
std::int64_t ToInt64(double d) {
  if (std::isnan(d)) return 0;
  if (d >= 9.2e18) return INT64_MAX;
  if (d <= -9.2e18) return INT64_MIN;
  return static_cast<std::int64_t>(d);
}

template <typename T>
const T* Pick(const std::vector<T>& v, ByteReader* in) {
  if (v.empty()) return nullptr;
  return &v[in->Byte() % v.size()];
}

std::vector<const Attr*> AttrsOf(const Inventory& inv, bool numeric) {
  std::vector<const Attr*> out;
  for (const auto& a : inv.attrs) {
    const bool num = a.cls == H5T_INTEGER || a.cls == H5T_FLOAT;
    if (numeric ? num : a.cls == H5T_STRING) out.push_back(&a);
  }
  return out;
}

/// Replaces attribute `name` of `obj` by one of `type` over `space` holding `data`.
void RewriteAttr(hid_t obj, const std::string& name, hid_t type, hid_t space, hid_t mem_type,
                 const void* data) {
  if (H5Aexists(obj, name.c_str()) > 0) H5Adelete(obj, name.c_str());
  Id attr(H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (attr.ok()) H5Awrite(attr.get(), mem_type, data);
}

void SetNumericAttr(hid_t file, const Inventory& inv, ByteReader* in) {
  const auto attrs = AttrsOf(inv, true);
  const Attr* const* pick = Pick(attrs, in);
  if (!pick) return;
  const Attr& a = **pick;
  Id obj(H5Oopen(file, a.object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!obj.ok()) return;
  std::vector<double> values;
  hid_t space_copy = -1;
  {
    Id attr(H5Aopen(obj.get(), a.name.c_str(), H5P_DEFAULT), H5Aclose);
    if (!attr.ok()) return;
    Id space(H5Aget_space(attr.get()), H5Sclose);
    const hssize_t n = H5Sget_simple_extent_npoints(space.get());
    if (n <= 0 || n > 4096) return;
    values.resize(static_cast<std::size_t>(n));
    if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, values.data()) < 0) return;
    space_copy = H5Scopy(space.get());
  }
  Id space(space_copy, H5Sclose);
  const std::uint8_t mode = in->Byte();
  values[mode % values.size()] = in->Double();
  Note("set attribute", a.object + "@" + a.name,
       std::to_string(values[mode % values.size()]) + ((mode & 0x80) ? " as float64" : ""));
  const bool retype_float = (mode & 0x80) != 0;  // an integer attribute stored as float64
  if (a.cls == H5T_INTEGER && !retype_float) {
    std::vector<std::int64_t> ints(values.size());
    std::transform(values.begin(), values.end(), ints.begin(), ToInt64);
    RewriteAttr(obj.get(), a.name, H5T_STD_I64LE, space.get(), H5T_NATIVE_INT64, ints.data());
  } else {
    RewriteAttr(obj.get(), a.name, H5T_IEEE_F64LE, space.get(), H5T_NATIVE_DOUBLE, values.data());
  }
}

std::string StringAttrValue(hid_t file, const Attr& a) {
  Id obj(H5Oopen(file, a.object.c_str(), H5P_DEFAULT), H5Oclose);
  Id attr(H5Aopen(obj.get(), a.name.c_str(), H5P_DEFAULT), H5Aclose);
  Id type(H5Aget_type(attr.get()), H5Tclose);
  Id space(H5Aget_space(attr.get()), H5Sclose);
  if (!type.ok() || H5Tis_variable_str(type.get()) > 0 ||
      H5Sget_simple_extent_npoints(space.get()) != 1)
    return "";
  std::string s(H5Tget_size(type.get()), '\0');
  if (H5Aread(attr.get(), type.get(), s.data()) < 0) return "";
  s.resize(std::string(s.c_str()).size());
  return s;
}

void SetStringAttr(hid_t file, const Inventory& inv, ByteReader* in) {
  const auto attrs = AttrsOf(inv, false);
  const Attr* const* pick = Pick(attrs, in);
  if (!pick) return;
  const Attr& a = **pick;
  std::string value;
  const std::uint8_t mode = in->Byte();
  if (mode % 3 == 0) {  // a short string from the bytes
    const int len = in->Byte() % 12;
    for (int i = 0; i < len; ++i) value += static_cast<char>(in->Byte());
  } else if (mode % 3 == 1) {  // another string attribute's value
    const Attr* const* other = Pick(attrs, in);
    value = StringAttrValue(file, **other);
  } else {  // its own value with one character changed (or cut short)
    value = StringAttrValue(file, a);
    const std::uint8_t at = in->Byte(), c = in->Byte();
    if (!value.empty()) {
      if (c & 1)
        value.resize(at % value.size());
      else
        value[at % value.size()] = static_cast<char>(c >> 1);
    }
  }
  Note("set string attribute", a.object + "@" + a.name, "'" + value + "'");
  Id obj(H5Oopen(file, a.object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!obj.ok()) return;
  Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  RewriteAttr(obj.get(), a.name, type.get(), space.get(), type.get(), padded.data());
}

void DeleteAttr(hid_t file, const Inventory& inv, ByteReader* in) {
  const Attr* a = Pick(inv.attrs, in);
  if (!a) return;
  Note("delete attribute", a->object + "@" + a->name);
  H5Adelete_by_name(file, a->object.c_str(), a->name.c_str(), H5P_DEFAULT);
}

void DeleteDataset(hid_t file, const Inventory& inv, ByteReader* in) {
  const std::string* d = Pick(inv.datasets, in);
  if (!d) return;
  Note("delete dataset", *d);
  H5Ldelete(file, d->c_str(), H5P_DEFAULT);
}

/// A numeric dataset's values (as double), dims and class; false for strings and other types.
bool ReadNumeric(hid_t file, const std::string& name, std::vector<double>* values,
                 std::vector<hsize_t>* dims, H5T_class_t* cls) {
  Id ds(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.ok()) return false;
  Id type(H5Dget_type(ds.get()), H5Tclose);
  *cls = H5Tget_class(type.get());
  if (*cls != H5T_INTEGER && *cls != H5T_FLOAT) return false;
  Id space(H5Dget_space(ds.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0 || rank > 8) return false;
  dims->assign(static_cast<std::size_t>(rank), 0);
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims->data(), nullptr);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0 || n > (1 << 22)) return false;
  values->assign(static_cast<std::size_t>(n), 0.0);
  return n == 0 ||
         H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values->data()) >= 0;
}

/// Replaces dataset `name` by one of file type `type` and `dims` holding `values`.
void WriteNumeric(hid_t file, const std::string& name, hid_t type, const std::vector<hsize_t>& dims,
                  const std::vector<double>& values) {
  H5Ldelete(file, name.c_str(), H5P_DEFAULT);
  Id space(dims.empty() ? H5Screate(H5S_SCALAR)
                        : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
           H5Sclose);
  Id ds(H5Dcreate2(file, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
        H5Dclose);
  if (!ds.ok() || values.empty()) return;
  if (H5Tget_class(type) == H5T_INTEGER) {
    // Saturating conversion done here: HDF5's own double -> integer conversion of NaN is undefined.
    std::vector<std::int64_t> ints(values.size());
    std::transform(values.begin(), values.end(), ints.begin(), ToInt64);
    H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, ints.data());
  } else {
    H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  }
}

hid_t FileTypeOf(H5T_class_t cls) { return cls == H5T_INTEGER ? H5T_STD_I64LE : H5T_IEEE_F64LE; }

hsize_t NewDim(hsize_t old, ByteReader* in) {
  switch (in->Byte() % 5) {
    case 0:
      return 0;
    case 1:
      return 1;
    case 2:
      return old + 1;
    case 3:
      return old > 0 ? old - 1 : 2;
    default:
      return in->Byte() % 17;
  }
}

void ReplaceDataset(hid_t file, const Inventory& inv, ByteReader* in) {
  const std::string* d = Pick(inv.datasets, in);
  if (!d) return;
  std::vector<double> old;
  std::vector<hsize_t> dims;
  H5T_class_t cls;
  if (!ReadNumeric(file, *d, &old, &dims, &cls)) cls = H5T_FLOAT;  // e.g. a string: now numbers
  const int rank = 1 + in->Byte() % 2;
  std::vector<hsize_t> nd(static_cast<std::size_t>(rank));
  std::size_t total = 1;
  for (int i = 0; i < rank; ++i) {
    nd[static_cast<std::size_t>(i)] =
        NewDim(i < static_cast<int>(dims.size()) ? dims[static_cast<std::size_t>(i)] : 1, in);
    total *= nd[static_cast<std::size_t>(i)];
  }
  if (total > 4096) return;
  std::vector<double> values(total);
  const std::size_t from_bytes = std::min<std::size_t>(total, in->Byte() % 4);
  for (std::size_t i = 0; i < total; ++i)
    values[i] = i < from_bytes ? in->Double() : (old.empty() ? 0.5 : old[i % old.size()]);
  std::string shape;
  for (auto n : nd) shape += std::to_string(n) + " ";
  Note("replace dataset", *d,
       "dims " + shape + "first " + (values.empty() ? "-" : std::to_string(values[0])));
  WriteNumeric(file, *d, FileTypeOf(cls), nd, values);
}

void SetDatasetElement(hid_t file, const Inventory& inv, ByteReader* in) {
  const std::string* d = Pick(inv.datasets, in);
  if (!d) return;
  std::vector<double> values;
  std::vector<hsize_t> dims;
  H5T_class_t cls;
  if (!ReadNumeric(file, *d, &values, &dims, &cls) || values.empty()) return;
  const std::size_t at = in->U32() % values.size();
  const double v = in->Double();
  Note("set element", *d, std::to_string(at) + " = " + std::to_string(v));
  Id ds(H5Dopen2(file, d->c_str(), H5P_DEFAULT), H5Dclose);
  Id space(H5Dget_space(ds.get()), H5Sclose);
  // One element in place (the dataset keeps its type and shape).
  std::vector<hsize_t> coord(dims.size());
  std::size_t rest = at;
  for (std::size_t k = dims.size(); k-- > 0;) {
    coord[k] = rest % dims[k];
    rest /= dims[k];
  }
  if (!dims.empty() && H5Sselect_elements(space.get(), H5S_SELECT_SET, 1, coord.data()) < 0) return;
  const hsize_t one = 1;
  Id mem(H5Screate_simple(1, &one, nullptr), H5Sclose);
  if (cls == H5T_INTEGER) {
    const std::int64_t iv = ToInt64(v);
    H5Dwrite(ds.get(), H5T_NATIVE_INT64, mem.get(), space.get(), H5P_DEFAULT, &iv);
  } else {
    H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, &v);
  }
}

void ChangeDatasetType(hid_t file, const Inventory& inv, ByteReader* in) {
  const std::string* d = Pick(inv.datasets, in);
  if (!d) return;
  std::vector<double> values;
  std::vector<hsize_t> dims;
  H5T_class_t cls;
  if (!ReadNumeric(file, *d, &values, &dims, &cls)) return;
  static const hid_t* const kTypes[] = {&H5T_IEEE_F64LE_g, &H5T_IEEE_F32LE_g, &H5T_STD_I64LE_g,
                                        &H5T_STD_U8LE_g};
  const int which = in->Byte() % 4;
  const hid_t type = *kTypes[which];
  Note("retype dataset", *d, std::to_string(which) + " (f64 f32 i64 u8)");
  WriteNumeric(file, *d, type, dims, values);
}

}  // namespace

std::vector<std::uint8_t> ReadFileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(f),
                                  std::istreambuf_iterator<char>()};
  if (!f.good() && !f.eof()) bytes.clear();
  if (bytes.empty()) {
    std::fprintf(stderr, "fuzz: cannot read base artifact %s\n", path.c_str());
    std::abort();
  }
  return bytes;
}

void MutateH5(const std::string& path, ByteReader* in) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Id file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) {
    std::fprintf(stderr, "fuzz: cannot open %s for editing\n", path.c_str());
    std::abort();
  }
  const int edits = 1 + in->Byte() % 4;
  for (int e = 0; e < edits && !in->empty(); ++e) {
    const Inventory inv = Collect(file.get());  // again: the previous edit may have removed objects
    switch (in->Byte() % 8) {
      case 0:
      case 1:
        SetNumericAttr(file.get(), inv, in);
        break;
      case 2:
        SetStringAttr(file.get(), inv, in);
        break;
      case 3:
        DeleteAttr(file.get(), inv, in);
        break;
      case 4:
        DeleteDataset(file.get(), inv, in);
        break;
      case 5:
        ReplaceDataset(file.get(), inv, in);
        break;
      case 6:
        SetDatasetElement(file.get(), inv, in);
        break;
      default:
        ChangeDatasetType(file.get(), inv, in);
        break;
    }
  }
}

}  // namespace foresight::fuzz
