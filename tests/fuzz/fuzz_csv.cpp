/// Fuzz harness: CSV tables (common::readCsv) and CSV initial states (md readInitialStateCsv).
#include "FuzzTarget.h"
#include "common/Csv.h"
#include "md/io/InitialState.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const granagg::fuzz::MemFile file(data, size);
  granagg::fuzz::guarded([&] { (void)granagg::common::readCsv(file.path()); });
  granagg::fuzz::guarded([&] { (void)granagg::md::readInitialStateCsv(file.path(), 10.0); });
  return 0;
}
