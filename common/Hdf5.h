#pragma once
/// \file Hdf5.h
/// The one layer of helpers over the HDF5 C API, for every module that reads or writes HDF5 (md's
/// H5MD writer, reader and checkpoint; analysis's trajectory reader and analysis.h5; fit-beta; the
/// tests): an RAII handle, attribute and dataset helpers, and the text of the last HDF5 error.
/// Debian ships no HDF5 C++ wrapper (docs/ARCHITECTURE.md), hence this file. Included by .cpp files
/// only: the modules' public headers do not include it, so their users need no HDF5 include path.
///
/// Every helper that can fail throws std::runtime_error whose message starts with the context
/// the caller passes (usually "'<file>': <object>") and ends with HDF5's own description.
#if __has_include(<hdf5.h>)
#include <hdf5.h>
#else
#include <hdf5/serial/hdf5.h>  // Debian's serial HDF5 when the include path is not set (tests)
#endif

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/Strings.h"

namespace granagg::common::h5 {

/// Turns off HDF5's automatic printing of its error stack to stderr; our exceptions carry the
/// message instead. Affects the calling thread's default error stack (HDF5 keeps one per thread).
inline void silenceErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

/// HDF5's POSIX driver describes a failed read or write in one long text over two lines
/// ("file write failed: time = ..., filename = ..., errno = 28, error message = 'No space left on
/// device', buf = ..."): this keeps what a person needs, "file write failed: the disk is full
/// (No space left on device)". Other texts are returned unchanged.
inline std::string conciseIoError(const std::string& text) {
  const std::size_t m = text.find("error message = '");
  const std::size_t colon = text.find(':');
  if (m == std::string::npos || colon == std::string::npos || colon > m) return text;
  const std::size_t b = m + 17, e = text.find('\'', b);
  const std::string why = text.substr(b, e == std::string::npos ? std::string::npos : e - b);
  std::string head = text.substr(0, colon) + ": ";
  const std::size_t en = text.find("errno = ");
  const int err = en == std::string::npos ? 0 : std::atoi(text.c_str() + en + 8);
  return head + (err > 0 ? writeErrorReason(err) : why);
}

/// The most specific message on HDF5's current error stack ("" when empty), e.g.
/// "truncated file: eof = 1024, sblock->base_addr = 0, stored_eof = 4096".
inline std::string lastError() {
  struct Walk {
    std::string text;
  } walk;
  auto cb = [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
    auto* w = static_cast<Walk*>(data);
    if (n == 0 && err && err->desc) w->text = err->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, cb, &walk);
  H5Eclear2(H5E_DEFAULT);
  return conciseIoError(walk.text);
}

/// Throws std::runtime_error("<context>: <HDF5 message>").
[[noreturn]] inline void fail(const std::string& context) {
  const std::string msg = lastError();
  throw std::runtime_error(context + (msg.empty() ? std::string() : " (HDF5: " + msg + ")"));
}

/// Owning HDF5 identifier (file, group, dataset, dataspace, datatype, attribute or property
/// list); closes it with the matching H5?close on destruction. Move-only. Never wrap the
/// library's predefined types (H5T_NATIVE_DOUBLE...): they are not ours to close.
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
  /// The raw identifier (negative when invalid).
  hid_t get() const { return m_id; }
  /// True when the identifier is valid.
  bool valid() const { return m_id >= 0; }
  explicit operator bool() const { return valid(); }
  /// Closes the object now; returns false if HDF5 reported an error while closing (e.g. a
  /// failed write of cached data when closing a file).
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

/// Returns `Handle(id)` or throws (via fail) when id is negative.
inline Handle check(hid_t id, const std::string& context) {
  if (id < 0) fail(context);
  return Handle(id);
}

/// Throws (via fail) when an herr_t is negative.
inline void checkStatus(herr_t rc, const std::string& context) {
  if (rc < 0) fail(context);
}

/// True if the slash-separated `path` below `loc` exists (every component is checked, so a
/// missing intermediate group answers false instead of failing). Soft links are not followed
/// beyond existence of the link itself.
inline bool exists(hid_t loc, const std::string& path) {
  std::string partial;
  std::size_t start = (!path.empty() && path[0] == '/') ? 1 : 0;
  if (start) partial = "/";
  while (start <= path.size()) {
    std::size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    if (end > start) {
      if (!partial.empty() && partial.back() != '/') partial += '/';
      partial += path.substr(start, end - start);
      const htri_t e = H5Lexists(loc, partial.c_str(), H5P_DEFAULT);
      if (e <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    start = end + 1;
  }
  return true;
}

/// Kind of object at `path` (H5I_GROUP, H5I_DATASET...) or H5I_BADID if absent.
inline H5I_type_t objectType(hid_t loc, const std::string& path) {
  if (!exists(loc, path)) return H5I_BADID;
  Handle obj(H5Oopen(loc, path.c_str(), H5P_DEFAULT));
  if (!obj) {
    H5Eclear2(H5E_DEFAULT);
    return H5I_BADID;
  }
  return H5Iget_type(obj.get());
}

/// Frees the strings HDF5 allocated when reading variable-length strings.
inline void reclaimStrings(hid_t mem_type, hid_t space, void* buf) {
#if H5_VERSION_GE(1, 12, 0)
  H5Treclaim(mem_type, space, H5P_DEFAULT, buf);
#else
  H5Dvlen_reclaim(mem_type, space, H5P_DEFAULT, buf);
#endif
}

/// Names of the links directly under group `loc`, in increasing name order (what h5py lists).
inline std::vector<std::string> children(hid_t loc) {
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  if (H5Literate(loc, H5_INDEX_NAME, H5_ITER_INC, nullptr, cb, &names) < 0) H5Eclear2(H5E_DEFAULT);
  return names;
}

/// Current extent of a dataset or attribute dataspace (empty for a scalar).
inline std::vector<hsize_t> spaceDims(hid_t space) {
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank <= 0) return {};
  std::vector<hsize_t> d(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, d.data(), nullptr);
  return d;
}

/// Current extent of a dataset (empty for a scalar); throws on error.
inline std::vector<hsize_t> datasetDims(hid_t dset, const std::string& context) {
  Handle space = check(H5Dget_space(dset), context + ": cannot read the dataspace");
  return spaceDims(space.get());
}

/// Creates a group (intermediate groups are created too).
inline Handle createGroup(hid_t loc, const std::string& path, const std::string& context) {
  Handle lcpl = check(H5Pcreate(H5P_LINK_CREATE), context);
  checkStatus(H5Pset_create_intermediate_group(lcpl.get(), 1), context);
  return check(H5Gcreate2(loc, path.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
               context + ": cannot create group '" + path + "'");
}

/// Fixed-length, NUL-terminated ASCII string type of `len` characters (len >= 1).
inline Handle fixedStringType(std::size_t len) {
  Handle t(H5Tcopy(H5T_C_S1));
  H5Tset_size(t.get(), len == 0 ? 1 : len + 1);
  H5Tset_strpad(t.get(), H5T_STR_NULLTERM);
  H5Tset_cset(t.get(), H5T_CSET_ASCII);
  return t;
}

/// Variable-length UTF-8 string type (h5py reads it back as `str`).
inline Handle varStringType() {
  Handle t(H5Tcopy(H5T_C_S1));
  H5Tset_size(t.get(), H5T_VARIABLE);
  H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

/// Writes a numeric attribute of rank 0 (scalar, dims empty) or rank 1+; `file_type` is the
/// stored type (H5T_STD_I32LE...), `mem_type` the native one.
inline void writeAttribute(hid_t obj, const std::string& name, hid_t file_type, hid_t mem_type,
                           const void* data, const std::vector<hsize_t>& dims,
                           const std::string& context) {
  Handle space =
      dims.empty() ? Handle(H5Screate(H5S_SCALAR))
                   : Handle(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  Handle attr =
      check(H5Acreate2(obj, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
            context + ": cannot create attribute '" + name + "'");
  checkStatus(H5Awrite(attr.get(), mem_type, data),
              context + ": cannot write attribute '" + name + "'");
}

inline void writeAttribute(hid_t obj, const std::string& name, std::int64_t v,
                           const std::string& ctx) {
  writeAttribute(obj, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &v, {}, ctx);
}
inline void writeAttribute(hid_t obj, const std::string& name, double v, const std::string& ctx) {
  writeAttribute(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v, {}, ctx);
}

/// Scalar fixed-length ASCII string attribute (the H5MD metadata strings).
inline void writeFixedStringAttribute(hid_t obj, const std::string& name, const std::string& value,
                                      const std::string& ctx) {
  Handle type = fixedStringType(value.size());
  std::vector<char> buf(value.size() + 1, '\0');
  value.copy(buf.data(), value.size());
  writeAttribute(obj, name, type.get(), type.get(), buf.data(), {}, ctx);
}

/// 1D fixed-length ASCII string array attribute (e.g. box boundary = ["periodic", ...]).
inline void writeFixedStringArrayAttribute(hid_t obj, const std::string& name,
                                           const std::vector<std::string>& values,
                                           const std::string& ctx) {
  std::size_t len = 1;
  for (const auto& v : values) len = std::max(len, v.size());
  Handle type = fixedStringType(len);
  const std::size_t stride = len + 1;
  std::vector<char> buf(values.size() * stride, '\0');
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i].copy(buf.data() + i * stride, values[i].size());
  writeAttribute(obj, name, type.get(), type.get(), buf.data(), {values.size()}, ctx);
}

/// Scalar variable-length UTF-8 string attribute (any length: the text lives in the global heap).
inline void writeStringAttribute(hid_t obj, const std::string& name, const std::string& value,
                                 const std::string& ctx) {
  Handle type = varStringType();
  const char* p = value.c_str();
  writeAttribute(obj, name, type.get(), type.get(), &p, {}, ctx);
}

/// Scalar variable-length UTF-8 string dataset (e.g. the TOML text of the configuration).
inline void writeStringDataset(hid_t loc, const std::string& name, const std::string& value,
                               const std::string& ctx) {
  Handle type = varStringType();
  Handle space(H5Screate(H5S_SCALAR));
  Handle dset = check(
      H5Dcreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      ctx + ": cannot create dataset '" + name + "'");
  const char* p = value.c_str();
  checkStatus(H5Dwrite(dset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p),
              ctx + ": cannot write dataset '" + name + "'");
}

/// Bytes a dataset may claim beyond what it stores: fill values of chunks never written, and
/// granagg's own small datasets. Above it the claim must be backed by stored bytes.
inline constexpr double UNSTORED_ALLOWANCE_BYTES = 16.0 * (1 << 20);
/// The largest expansion of a filtered (compressed) dataset: zlib's deflate, the filter that
/// HDF5 writers use, expands its input at most about 1032-fold (RFC 1951's longest match of 258
/// bytes in a code of 2 bits); shuffle and fletcher32 do not change the size.
inline constexpr double MAX_FILTER_EXPANSION = 1100.0;

/// "1.2 GB", "34.0 kB": a byte count for error messages (decimal units).
inline std::string byteText(double bytes) {
  const char* unit[] = {"bytes", "kB", "MB", "GB", "TB", "PB", "EB"};
  int k = 0;
  while (bytes >= 1000.0 && k < 6) {
    bytes /= 1000.0;
    ++k;
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, k == 0 ? "%.0f %s" : "%.1f %s", bytes, unit[k]);
  return buf;
}

/// Checks, before anything is allocated, that a dataset's extent is backed by the bytes the file
/// stores for it: a corrupt or hostile file can claim 1e12 particles in a header of a few bytes,
/// which would otherwise end in std::bad_alloc or an allocation of the whole memory. Throws
/// std::invalid_argument (bad input: the CLI's exit status 2) naming the dataset (ctx).
inline void checkStoredSize(hid_t dset, const std::string& ctx) {
  const std::vector<hsize_t> dims = datasetDims(dset, ctx);
  Handle type = check(H5Dget_type(dset), ctx + ": cannot read its type");
  double claimed = static_cast<double>(H5Tget_size(type.get()));
  std::string shape;
  for (hsize_t d : dims) {
    claimed *= static_cast<double>(d);
    shape += (shape.empty() ? "" : " x ") + std::to_string(d);
  }
  if (claimed <= UNSTORED_ALLOWANCE_BYTES) return;
  Handle dcpl = check(H5Dget_create_plist(dset), ctx + ": cannot read its creation properties");
  const bool filtered = H5Pget_nfilters(dcpl.get()) > 0;
  const double stored = static_cast<double>(H5Dget_storage_size(dset));
  if (claimed <= UNSTORED_ALLOWANCE_BYTES + stored * (filtered ? MAX_FILTER_EXPANSION : 1.0))
    return;
  throw std::invalid_argument(ctx + " claims " + (shape.empty() ? "one" : shape) +
                              " values (" + byteText(claimed) + ") but the file stores " +
                              byteText(stored) + " for it (a corrupt or truncated file?)");
}

/// The same for an attribute: granagg reads only small attributes (units, box dimension,
/// strings), so one that claims more than UNSTORED_ALLOWANCE_BYTES is refused.
inline void checkAttributeSize(hid_t type, hid_t space, const std::string& ctx) {
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  const double claimed = static_cast<double>(n > 0 ? n : 0) *
                         static_cast<double>(H5Tget_size(type));
  if (n < 0 || claimed > UNSTORED_ALLOWANCE_BYTES)
    throw std::invalid_argument(ctx + " claims " + std::to_string(n) + " values (" +
                                byteText(claimed) + "), more than an attribute of a granagg " +
                                "input holds (a corrupt file?)");
}

/// Reads a string stored in an attribute or a scalar dataset of fixed or variable length.
/// `is_attr` selects H5Aread/H5Dread. Throws when the object is not a scalar string.
inline std::string readString(hid_t obj, bool is_attr, const std::string& ctx) {
  Handle type =
      check(is_attr ? H5Aget_type(obj) : H5Dget_type(obj), ctx + ": cannot read its type");
  if (H5Tget_class(type.get()) != H5T_STRING) throw std::runtime_error(ctx + ": not a string");
  Handle space =
      check(is_attr ? H5Aget_space(obj) : H5Dget_space(obj), ctx + ": cannot read its dataspace");
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    throw std::runtime_error(ctx + ": not a single string");
  if (is_attr)
    checkAttributeSize(type.get(), space.get(), ctx);
  else
    checkStoredSize(obj, ctx);
  if (H5Tis_variable_str(type.get()) > 0) {
    Handle mem = varStringType();
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));
    char* p = nullptr;
    const herr_t rc = is_attr ? H5Aread(obj, mem.get(), &p)
                              : H5Dread(obj, mem.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p);
    if (rc < 0) fail(ctx + ": cannot read");
    std::string s = p ? p : "";
    reclaimStrings(mem.get(), space.get(), &p);
    return s;
  }
  const std::size_t n = H5Tget_size(type.get());
  std::vector<char> buf(n + 1, '\0');
  const herr_t rc = is_attr ? H5Aread(obj, type.get(), buf.data())
                            : H5Dread(obj, type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
  if (rc < 0) fail(ctx + ": cannot read");
  std::string s(buf.data(), n);
  s.resize(std::char_traits<char>::length(s.c_str()));  // fixed-length: up to the first NUL
  while (!s.empty() && s.back() == ' ') s.pop_back();   // space-padded strings (Fortran writers)
  return s;
}

/// Reads a 1D array of fixed- or variable-length strings from an attribute.
inline std::vector<std::string> readStringArrayAttribute(hid_t attr, const std::string& ctx) {
  Handle type = check(H5Aget_type(attr), ctx + ": cannot read its type");
  if (H5Tget_class(type.get()) != H5T_STRING)
    throw std::runtime_error(ctx + ": not a string attribute");
  Handle space = check(H5Aget_space(attr), ctx + ": cannot read its dataspace");
  checkAttributeSize(type.get(), space.get(), ctx);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  std::vector<std::string> out;
  if (n <= 0) return out;
  if (H5Tis_variable_str(type.get()) > 0) {
    Handle mem = varStringType();
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));
    std::vector<char*> ptrs(static_cast<std::size_t>(n), nullptr);
    if (H5Aread(attr, mem.get(), ptrs.data()) < 0) fail(ctx + ": cannot read");
    for (char* p : ptrs) out.emplace_back(p ? p : "");
    reclaimStrings(mem.get(), space.get(), ptrs.data());
    return out;
  }
  const std::size_t len = H5Tget_size(type.get());
  std::vector<char> buf(len * static_cast<std::size_t>(n) + 1, '\0');
  if (H5Aread(attr, type.get(), buf.data()) < 0) fail(ctx + ": cannot read");
  for (hssize_t i = 0; i < n; ++i) {
    std::string s(buf.data() + static_cast<std::size_t>(i) * len, len);
    s.resize(std::char_traits<char>::length(s.c_str()));
    while (!s.empty() && s.back() == ' ') s.pop_back();
    out.push_back(s);
  }
  return out;
}

/// Reads all elements of a numeric attribute converted to `mem_type` (H5T_NATIVE_DOUBLE,
/// H5T_NATIVE_INT64...). T must match mem_type.
template <class T>
std::vector<T> readNumericAttribute(hid_t attr, hid_t mem_type, const std::string& ctx) {
  Handle type = check(H5Aget_type(attr), ctx + ": cannot read its type");
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) throw std::runtime_error(ctx + ": not a number");
  Handle space = check(H5Aget_space(attr), ctx + ": cannot read its dataspace");
  checkAttributeSize(type.get(), space.get(), ctx);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  std::vector<T> out(static_cast<std::size_t>(n > 0 ? n : 0));
  if (!out.empty() && H5Aread(attr, mem_type, out.data()) < 0) fail(ctx + ": cannot read");
  return out;
}

/// Opens the attribute `name` of `obj`, or returns an invalid handle when it does not exist.
inline Handle openAttribute(hid_t obj, const std::string& name) {
  const htri_t e = H5Aexists(obj, name.c_str());
  if (e <= 0) {
    H5Eclear2(H5E_DEFAULT);
    return Handle();
  }
  return Handle(H5Aopen(obj, name.c_str(), H5P_DEFAULT));
}

/// Creates a chunked dataset whose first dimension is unlimited (a time series `value`, `step`
/// or `time`): shape [0, inner...], chunk [1 or chunk0, inner...].
/// `inner_chunk` (same length as `inner`) overrides the chunk extent of the inner dimensions
/// (default: whole inner extents).
inline Handle createExtendible(hid_t loc, const std::string& name, hid_t file_type,
                               const std::vector<hsize_t>& inner, hsize_t chunk0,
                               const std::string& ctx,
                               const std::vector<hsize_t>& inner_chunk = {}) {
  std::vector<hsize_t> dims{0}, maxdims{H5S_UNLIMITED}, chunk{chunk0};
  for (std::size_t k = 0; k < inner.size(); ++k) {
    const hsize_t d = inner[k];
    dims.push_back(d);
    maxdims.push_back(d);
    const hsize_t c = k < inner_chunk.size() ? inner_chunk[k] : d;
    chunk.push_back(c == 0 ? 1 : c);
  }
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()));
  Handle dcpl = check(H5Pcreate(H5P_DATASET_CREATE), ctx);
  checkStatus(H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()),
              ctx + ": chunking '" + name + "'");
  return check(
      H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
      ctx + ": cannot create dataset '" + name + "'");
}

/// File and memory dataspaces selecting rows [row, row + count) of a dataset whose current
/// dimensions are `dims` (first dimension = time index); shared by writeRows and readRows.
inline void selectRows(hid_t dset, const std::vector<hsize_t>& dims, hsize_t row, hsize_t count,
                       Handle& fspace, Handle& mspace, const std::string& ctx) {
  fspace = check(H5Dget_space(dset), ctx);
  std::vector<hsize_t> start(dims.size(), 0), cnt = dims;
  start[0] = row;
  cnt[0] = count;
  checkStatus(
      H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr),
      ctx);
  mspace = Handle(H5Screate_simple(static_cast<int>(cnt.size()), cnt.data(), nullptr));
}

/// Names of all attributes of an object, in name order.
inline std::vector<std::string> attributeNames(hid_t obj, const std::string& ctx) {
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5A_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Aiterate2(obj, H5_INDEX_NAME, H5_ITER_INC, &idx, cb, &names) < 0)
    fail(ctx + ": cannot list the attributes");
  return names;
}

/// Names of the links (datasets, groups) of a group, in name order.
inline std::vector<std::string> datasetNames(hid_t group, const std::string& ctx) {
  std::vector<std::string> names;
  auto cb = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &idx, cb, &names) < 0)
    fail(ctx + ": cannot list the datasets");
  return names;
}

/// Writes rows [row, row + count) of a dataset whose first dimension is the time index, growing
/// it to at least row + count rows first. `data` holds count * (product of inner dims) values of
/// `mem_type`.
inline void writeRows(hid_t dset, hsize_t row, hsize_t count, hid_t mem_type, const void* data,
                      const std::string& ctx) {
  std::vector<hsize_t> dims = datasetDims(dset, ctx);
  if (dims.empty()) throw std::runtime_error(ctx + ": expected a time series, found a scalar");
  if (dims[0] < row + count) {
    dims[0] = row + count;
    checkStatus(H5Dset_extent(dset, dims.data()), ctx + ": cannot extend");
  }
  Handle fspace, mspace;
  selectRows(dset, dims, row, count, fspace, mspace, ctx);
  checkStatus(H5Dwrite(dset, mem_type, mspace.get(), fspace.get(), H5P_DEFAULT, data),
              ctx + ": cannot write");
}

/// Reads rows [row, row + count) of a dataset (first dimension = time index) into `out`, which
/// must hold count * (product of the other dims) values of `mem_type`; HDF5 converts types.
inline void readRows(hid_t dset, hsize_t row, hsize_t count, hid_t mem_type, void* out,
                     const std::string& ctx) {
  const std::vector<hsize_t> dims = datasetDims(dset, ctx);
  if (dims.empty() || dims[0] < row + count)
    throw std::runtime_error(ctx + ": rows " + std::to_string(row) + ".." +
                             std::to_string(row + count) + " requested, dataset has " +
                             std::to_string(dims.empty() ? 0 : dims[0]));
  Handle fspace, mspace;
  selectRows(dset, dims, row, count, fspace, mspace, ctx);
  checkStatus(H5Dread(dset, mem_type, mspace.get(), fspace.get(), H5P_DEFAULT, out),
              ctx + ": cannot read");
}

/// Reads a whole dataset converted to `mem_type` (T must match it).
template <class T>
std::vector<T> readAll(hid_t dset, hid_t mem_type, const std::string& ctx) {
  checkStoredSize(dset, ctx);
  const std::vector<hsize_t> dims = datasetDims(dset, ctx);
  std::size_t n = 1;
  for (hsize_t d : dims) n *= static_cast<std::size_t>(d);
  std::vector<T> out(n);
  if (n > 0)
    checkStatus(H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()),
                ctx + ": cannot read");
  return out;
}

/// A scalar string attribute `name` of `obj` (fixed or variable length) as text; "" when it is not
/// a string. Throws when the attribute does not exist or cannot be read.
inline std::string readStringAttribute(hid_t obj, const std::string& name,
                                       const std::string& context) {
  Handle attr = openAttribute(obj, name);
  if (!attr) fail(context + ": cannot open attribute '" + name + "'");
  Handle type = check(H5Aget_type(attr.get()), context);
  if (H5Tget_class(type.get()) != H5T_STRING) return "";
  return readString(attr.get(), true, context + ": attribute '" + name + "'");
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

}  // namespace granagg::common::h5
