#pragma once
/// \file Hdf5Lite.h
/// The few HDF5 C-API helpers analysis/ needs: an RAII handle, existence checks, row reads of
/// time series, string attributes, and small dataset writes for analysis.h5.
///
/// md/io/Hdf5Util.h holds a superset of these; analysis/ may not include md/ (design.md section 5),
/// hence this short copy. If Hdf5Util.h moves to common/, this file can go.
/// Every helper that fails throws std::runtime_error "<context> (HDF5: <message>)".
#if __has_include(<hdf5.h>)
#include <hdf5.h>
#else
#include <hdf5/serial/hdf5.h>  // Debian's serial HDF5 when the include path is not set (tests)
#endif

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace granagg::analysis::h5 {

/// Stops HDF5 from printing its error stack; our exceptions carry the message instead.
inline void silenceErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

/// The innermost message on HDF5's error stack ("" if none); clears the stack.
inline std::string lastError() {
  std::string text;
  auto cb = [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
    if (n == 0 && err && err->desc) *static_cast<std::string*>(data) = err->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, cb, &text);
  H5Eclear2(H5E_DEFAULT);
  return text;
}

[[noreturn]] inline void fail(const std::string& context) {
  const std::string msg = lastError();
  throw std::runtime_error(context + (msg.empty() ? std::string() : " (HDF5: " + msg + ")"));
}

/// Owning identifier; closes with the matching H5?close. Never wrap predefined types.
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : m_id(id) {}
  ~Handle() { reset(); }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : m_id(o.m_id) { o.m_id = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      m_id = o.m_id;
      o.m_id = H5I_INVALID_HID;
    }
    return *this;
  }
  hid_t get() const { return m_id; }
  explicit operator bool() const { return m_id >= 0; }
  /// Closes now; false if HDF5 reported an error while closing.
  bool reset() {
    if (m_id < 0) return true;
    herr_t rc = 0;
    switch (H5Iget_type(m_id)) {
      case H5I_FILE:
        rc = H5Fclose(m_id);
        break;
      case H5I_GROUP:
        rc = H5Gclose(m_id);
        break;
      case H5I_DATASET:
        rc = H5Dclose(m_id);
        break;
      case H5I_DATASPACE:
        rc = H5Sclose(m_id);
        break;
      case H5I_DATATYPE:
        rc = H5Tclose(m_id);
        break;
      case H5I_ATTR:
        rc = H5Aclose(m_id);
        break;
      case H5I_GENPROP_LST:
        rc = H5Pclose(m_id);
        break;
      default:
        rc = H5Idec_ref(m_id) < 0 ? -1 : 0;
        break;
    }
    m_id = H5I_INVALID_HID;
    return rc >= 0;
  }

 private:
  hid_t m_id = H5I_INVALID_HID;
};

inline Handle check(hid_t id, const std::string& context) {
  if (id < 0) fail(context);
  return Handle(id);
}
inline void checkStatus(herr_t rc, const std::string& context) {
  if (rc < 0) fail(context);
}

/// True if every component of the slash-separated `path` below `loc` exists.
inline bool exists(hid_t loc, const std::string& path) {
  std::string partial = (!path.empty() && path[0] == '/') ? "/" : "";
  std::size_t start = partial.size();
  while (start <= path.size()) {
    std::size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    if (end > start) {
      if (!partial.empty() && partial.back() != '/') partial += '/';
      partial += path.substr(start, end - start);
      if (H5Lexists(loc, partial.c_str(), H5P_DEFAULT) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    start = end + 1;
  }
  return true;
}

/// H5I_GROUP, H5I_DATASET... of the object at `path`, H5I_BADID when absent.
inline H5I_type_t objectType(hid_t loc, const std::string& path) {
  if (!exists(loc, path)) return H5I_BADID;
  Handle obj(H5Oopen(loc, path.c_str(), H5P_DEFAULT));
  if (!obj) {
    H5Eclear2(H5E_DEFAULT);
    return H5I_BADID;
  }
  return H5Iget_type(obj.get());
}

/// Link names directly under a group, in name order.
inline std::vector<std::string> children(hid_t loc) {
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  if (H5Literate(loc, H5_INDEX_NAME, H5_ITER_INC, nullptr, cb, &names) < 0) H5Eclear2(H5E_DEFAULT);
  return names;
}

/// Current extent of a dataset (empty for a scalar).
inline std::vector<hsize_t> dims(hid_t dset, const std::string& context) {
  Handle space = check(H5Dget_space(dset), context + ": cannot read the dataspace");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail(context + ": cannot read the rank");
  std::vector<hsize_t> d(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), d.data(), nullptr);
  return d;
}

/// Reads `count` rows from `row` of a dataset whose first dimension is time, converted to
/// `mem_type`; `out` holds count * (product of the inner dimensions) values.
inline void readRows(hid_t dset, hsize_t row, hsize_t count, hid_t mem_type, void* out,
                     const std::string& context) {
  const std::vector<hsize_t> d = dims(dset, context);
  if (d.empty() || d[0] < row + count)
    throw std::runtime_error(context + ": row " + std::to_string(row) + " requested, dataset has " +
                             std::to_string(d.empty() ? 0 : d[0]) + " rows");
  Handle fspace = check(H5Dget_space(dset), context);
  std::vector<hsize_t> start(d.size(), 0), cnt = d;
  start[0] = row;
  cnt[0] = count;
  checkStatus(
      H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr),
      context);
  Handle mspace(H5Screate_simple(static_cast<int>(cnt.size()), cnt.data(), nullptr));
  checkStatus(H5Dread(dset, mem_type, mspace.get(), fspace.get(), H5P_DEFAULT, out),
              context + ": cannot read");
}

/// Reads a whole dataset converted to `mem_type` (T must match it).
template <class T>
std::vector<T> readAll(hid_t dset, hid_t mem_type, const std::string& context) {
  std::size_t n = 1;
  for (hsize_t k : dims(dset, context)) n *= static_cast<std::size_t>(k);
  std::vector<T> out(n);
  if (n > 0)
    checkStatus(H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
                context + ": cannot read");
  return out;
}

/// A scalar string attribute (fixed or variable length) as text; "" when it is not a string.
inline std::string readStringAttribute(hid_t obj, const std::string& name,
                                       const std::string& context) {
  Handle attr(H5Aopen(obj, name.c_str(), H5P_DEFAULT));
  if (!attr) fail(context + ": cannot open attribute '" + name + "'");
  Handle type = check(H5Aget_type(attr.get()), context);
  if (H5Tget_class(type.get()) != H5T_STRING) return "";
  if (H5Tis_variable_str(type.get()) > 0) {
    Handle mem(H5Tcopy(H5T_C_S1));
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));
    char* p = nullptr;
    checkStatus(H5Aread(attr.get(), mem.get(), &p),
                context + ": cannot read attribute '" + name + "'");
    std::string s = p ? p : "";
    H5free_memory(p);
    return s;
  }
  const std::size_t n = H5Tget_size(type.get());
  std::vector<char> buf(n + 1, '\0');
  checkStatus(H5Aread(attr.get(), type.get(), buf.data()),
              context + ": cannot read attribute '" + name + "'");
  return std::string(buf.data());
}

/// Names of all attributes of an object.
inline std::vector<std::string> attributeNames(hid_t obj) {
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5A_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_INC, &idx, cb, &names) < 0) H5Eclear2(H5E_DEFAULT);
  return names;
}

/// Creates a group (with intermediate groups).
inline Handle createGroup(hid_t loc, const std::string& path, const std::string& context) {
  Handle lcpl = check(H5Pcreate(H5P_LINK_CREATE), context);
  checkStatus(H5Pset_create_intermediate_group(lcpl.get(), 1), context);
  return check(H5Gcreate2(loc, path.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
               context + ": cannot create group '" + path + "'");
}

/// Writes a whole dataset of shape `shape` (file type `file_type`, memory type `mem_type`).
inline void writeDataset(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type,
                         const std::vector<hsize_t>& shape, const void* data,
                         const std::string& context) {
  Handle space(shape.empty()
                   ? H5Screate(H5S_SCALAR)
                   : H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr));
  Handle d = check(
      H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      context + ": cannot create dataset '" + name + "'");
  checkStatus(H5Dwrite(d.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
              context + ": cannot write '" + name + "'");
}

/// Scalar variable-length UTF-8 string attribute.
inline void writeStringAttribute(hid_t obj, const std::string& name, const std::string& value,
                                 const std::string& context) {
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  Handle space(H5Screate(H5S_SCALAR));
  Handle a = check(H5Acreate2(obj, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   context + ": cannot create attribute '" + name + "'");
  const char* p = value.c_str();
  checkStatus(H5Awrite(a.get(), type.get(), &p),
              context + ": cannot write attribute '" + name + "'");
}

/// Scalar double attribute.
inline void writeNumberAttribute(hid_t obj, const std::string& name, double value,
                                 const std::string& context) {
  Handle space(H5Screate(H5S_SCALAR));
  Handle a =
      check(H5Acreate2(obj, name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
            context + ": cannot create attribute '" + name + "'");
  checkStatus(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, &value),
              context + ": cannot write attribute '" + name + "'");
}

}  // namespace granagg::analysis::h5
