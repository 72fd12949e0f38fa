/// Fuzz harness: LAMMPS text dumps as trajectories (analysis/io/LammpsDump.h), every frame.
#include "FuzzTarget.h"
#include "analysis/io/LammpsDump.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const granagg::fuzz::MemFile file(data, size);
  granagg::fuzz::guarded([&] {
    granagg::analysis::LammpsDump dump(file.path(), 0.001);
    granagg::analysis::Frame f;
    for (int k = 0; k < 64 && dump.next(f); ++k) {
    }
  });
  return 0;
}
