/// Fuzz harness: LAMMPS data files as initial states (md/io/InitialState.h,
/// readInitialStateLammps).
#include "FuzzTarget.h"
#include "md/io/InitialState.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const granagg::fuzz::MemFile file(data, size);
  granagg::fuzz::guarded([&] {
    (void)granagg::md::isLammpsData(file.path());
    (void)granagg::md::readInitialStateLammps(file.path());
  });
  return 0;
}
