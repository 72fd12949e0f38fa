/// Fuzz harness: H5MD trajectories and initial states from raw bytes, opened from memory through
/// HDF5's file-image API (common::H5mdReader::fromImage), so that no file is written. The seed
/// corpus holds real granagg trajectories. A crash inside libhdf5 itself (Debian's 1.10.8 has
/// known decoder bugs on malformed files) is recorded in docs/robustness.md, not counted as ours.
#include "FuzzTarget.h"
#include "ReadH5md.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  granagg::fuzz::guarded([&] {
    auto reader = granagg::common::H5mdReader::fromImage(data, size, "fuzz.h5");
    granagg::fuzz::readEverything(reader);
    reader.keepWrapCrossings(true);  // the initial-state reading
    granagg::fuzz::readEverything(reader);
  });
  return 0;
}
