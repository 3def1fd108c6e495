// libFuzzer target: the Victoria Park reader from memory. Input: controls.txt, then
// tree_observations_associated_UTS.txt, then gps.txt, separated by lines "%%".
#include "fuzz_events.hpp"

#include "io/victoria_park.hpp"

#include <Eigen/LU>
#include <cstdint>

namespace {
constexpr const char* kFiles[] = {"controls.txt", "tree_observations_associated_UTS.txt", "gps.txt"};
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  seif::VictoriaParkFiles files;
  files.folder = "fuzz";
  files.text = seif::fuzz::splitFiles(std::string_view(reinterpret_cast<const char*>(data), size), kFiles);
  seif::fuzz::drainOrAbort([&] { return seif::openVictoriaPark(files, {}); });
  return 0;
}
