// libFuzzer target: the Victoria Park reader from memory. Input: controls.txt, then
// tree_observations_associated_UTS.txt, then gps.txt, then tree_detections.txt, separated by
// lines "%%". The associated detections are read; when tree_detections.txt is there, the
// raw ones too (with the UTS file as truth).
#include "fuzz_events.hpp"

#include "io/victoria_park.hpp"

#include <Eigen/LU>
#include <cstdint>

namespace {
constexpr const char* kFiles[] = {"controls.txt", "tree_observations_associated_UTS.txt", "gps.txt",
                                  "tree_detections.txt"};
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  seif::VictoriaParkFiles files;
  files.folder = "fuzz";
  files.text = seif::fuzz::splitFiles(std::string_view(reinterpret_cast<const char*>(data), size), kFiles);
  seif::fuzz::drainOrAbort([&] { return seif::openVictoriaPark(files, {}); });
  if (files.text.count("tree_detections.txt") != 0) {
    seif::DatasetOptions raw;
    raw.detections = seif::Detections::Raw;
    seif::fuzz::drainOrAbort([&] { return seif::openVictoriaPark(files, raw); });
  }
  return 0;
}
