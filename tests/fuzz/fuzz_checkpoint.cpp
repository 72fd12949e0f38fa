/// Fuzz harness: checkpoints (md/io/Checkpoint.h, readCheckpoint), from raw bytes. The seed
/// corpus holds real checkpoints; libhdf5's own decoding is not instrumented, granagg's checks of
/// what it decodes are.
#include "FuzzTarget.h"
#include "md/io/Checkpoint.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const granagg::fuzz::ShmFile file(data, size);
  granagg::fuzz::guarded([&] { (void)granagg::md::readCheckpoint(file.path()); });
  return 0;
}
