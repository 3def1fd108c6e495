// libFuzzer target: the g2o reader from memory; every event must keep the readers' promises.
#include "fuzz_events.hpp"

#include <seif/io/graph_file.hpp>

#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  seif::fuzz::drainOrAbort([&] { return seif::openG2oText("fuzz", text); });
  return 0;
}
