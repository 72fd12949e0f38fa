/// Fuzz harness, structure-aware: writes a valid HDF5 file whose H5MD layout the input chooses
/// (which elements exist, dataset or group, shapes, stored types, row counts, attributes,
/// values including NaN and infinities), then reads it with granagg's reader from memory. It
/// tests granagg's logic over well-formed HDF5, where the raw harness mostly tests libhdf5's.
#include <string>
#include <vector>

#include "FuzzTarget.h"
#include "ReadH5md.h"

namespace {

using granagg::common::h5::Handle;
using granagg::fuzz::Bytes;

hid_t fileType(Bytes& in) {
  switch (in.byte() % 4) {
    case 0:
      return H5T_IEEE_F32LE;
    case 1:
      return H5T_STD_I32LE;
    case 2:
      return H5T_STD_I64LE;
    default:
      return H5T_IEEE_F64LE;
  }
}

/// A dataset of the given dims, written from fuzz values (converted to its stored type).
void dataset(hid_t loc, const char* name, std::vector<hsize_t> dims, Bytes& in) {
  hsize_t n = 1;
  for (hsize_t d : dims) n *= d;
  std::vector<double> v(n);
  for (auto& x : v) x = in.real();
  if (!dims.empty() && in.flag()) {  // sometimes the fixed-increment scalar form of step/time
    dims.clear();
    v.resize(1);
  }
  Handle space(dims.empty()
                   ? H5Screate(H5S_SCALAR)
                   : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  const hid_t type = fileType(in);
  Handle d(H5Dcreate2(loc, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!d.valid()) return;
  // integer types: values out of range are clipped by HDF5's conversion (no UB on our side)
  H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
}

void intAttribute(hid_t obj, const char* name, Bytes& in) {
  const hsize_t n = in.range(0, 3);
  std::vector<long long> v(n);
  for (auto& x : v) x = static_cast<long long>(in.range(0, 6)) - 1;
  Handle space(n == 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr));
  Handle a(H5Acreate2(obj, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (a.valid() && n > 0) H5Awrite(a.get(), H5T_NATIVE_LLONG, v.data());
}

void stringAttribute(hid_t obj, const char* name, Bytes& in) {
  const char* words[] = {"periodic", "none", "", "periodic periodic"};
  const hsize_t n = in.range(0, 4);
  std::vector<const char*> v(n);
  for (auto& w : v) w = words[in.byte() % 4];
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  Handle space(n == 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr));
  Handle a(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  if (a.valid() && n > 0) H5Awrite(a.get(), type.get(), v.data());
}

/// An element {value, step, time} (or a plain dataset) of `inner` dims per frame.
void element(hid_t part, const char* name, std::vector<hsize_t> inner, hsize_t frames, Bytes& in) {
  if (in.byte() % 8 == 0) return;  // missing
  for (auto& d : inner)
    if (in.byte() % 16 == 0) d = in.range(0, 4);  // a wrong shape now and then
  if (in.byte() % 6 == 0) {                       // time-independent dataset
    dataset(part, name, inner, in);
    return;
  }
  Handle g(H5Gcreate2(part, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!g.valid()) return;
  std::vector<hsize_t> dims{in.byte() % 5 == 0 ? in.range(0, 4) : frames};
  dims.insert(dims.end(), inner.begin(), inner.end());
  if (in.byte() % 10 != 0) dataset(g.get(), "value", dims, in);
  if (in.byte() % 10 != 0) dataset(g.get(), "step", {in.byte() % 7 == 0 ? frames + 1 : frames}, in);
  if (in.byte() % 4 != 0) dataset(g.get(), "time", {frames}, in);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  granagg::common::h5::silenceErrors();
  Bytes in(data, size);
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS));
  H5Pset_fapl_core(fapl.get(), 1 << 16, 0);  // in memory, never written to disk
  Handle file(H5Fcreate("struct.h5", H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
  if (!file.valid()) granagg::fuzz::defect("H5Fcreate", "core driver");
  const hid_t f = file.get();
  if (in.flag()) {
    Handle h5md(H5Gcreate2(f, "h5md", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (in.flag()) intAttribute(h5md.get(), "version", in);
  }
  const hsize_t n = in.range(0, 5), frames = in.range(0, 4);
  const char* group = in.flag() ? "all" : "other";
  if (in.byte() % 8 != 0) {
    Handle lcpl(H5Pcreate(H5P_LINK_CREATE));
    H5Pset_create_intermediate_group(lcpl.get(), 1);
    Handle part(H5Gcreate2(f, (std::string("particles/") + group).c_str(), lcpl.get(), H5P_DEFAULT,
                           H5P_DEFAULT));
    if (part.valid()) {
      element(part.get(), "position", {n, 3}, frames, in);
      element(part.get(), "velocity", {n, 3}, frames, in);
      element(part.get(), "charge", {n}, frames, in);
      element(part.get(), "image", {n, 3}, frames, in);
      if (in.byte() % 8 != 0) {
        Handle box(H5Gcreate2(part.get(), "box", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
        if (in.flag()) intAttribute(box.get(), "dimension", in);
        if (in.flag()) stringAttribute(box.get(), "boundary", in);
        element(box.get(), "edges",
                in.flag() ? std::vector<hsize_t>{3} : std::vector<hsize_t>{3, 3}, frames, in);
      }
    }
  }
  if (in.flag()) {
    Handle obs(H5Gcreate2(f, "observables", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (obs.valid()) element(obs.get(), "energy", {}, frames, in);
  }
  H5Fflush(f, H5F_SCOPE_GLOBAL);
  const ssize_t bytes = H5Fget_file_image(f, nullptr, 0);
  if (bytes <= 0) granagg::fuzz::defect("H5Fget_file_image", "no image");
  std::vector<char> image(static_cast<std::size_t>(bytes));
  H5Fget_file_image(f, image.data(), image.size());
  file.reset();
  granagg::fuzz::guarded([&] {
    auto reader = granagg::common::H5mdReader::fromImage(image.data(), image.size(), "struct.h5");
    granagg::fuzz::readEverything(reader);
  });
  return 0;
}
