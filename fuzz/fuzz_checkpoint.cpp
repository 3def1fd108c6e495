// libFuzzer target: checkpoints from memory (seif::loadFromBytes). Each input is loaded
// twice: as it is, and with its header's payload size and checksum made to match (so that
// the fuzzer reaches the payload's parser, not only the checksum). Either must load or
// throw seif::DataError with a printable message; a loaded filter must then take a step.
#include "fuzz_support.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/checkpoint.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

std::string resealed(std::string bytes) {
  if (bytes.size() < 32) return bytes;
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 of the payload
  for (std::size_t i = 32; i < bytes.size(); ++i) {
    h ^= static_cast<unsigned char>(bytes[i]);
    h *= 0x100000001b3ull;
  }
  const std::uint64_t size = bytes.size() - 32;
  for (int i = 0; i < 8; ++i) {
    bytes[static_cast<std::size_t>(16 + i)] = static_cast<char>((size >> (8 * i)) & 0xFF);
    bytes[static_cast<std::size_t>(24 + i)] = static_cast<char>((h >> (8 * i)) & 0xFF);
  }
  return bytes;
}

void loadOrAbort(const std::string& bytes) {
  std::unique_ptr<seif::SlamFilter> filter;
  try {
    filter = seif::loadFromBytes(bytes, "fuzz");
  } catch (const seif::DataError& e) {
    if (!seif::fuzz::isPrintable(e.what())) {
      std::fprintf(stderr, "unprintable DataError message\n");
      std::abort();
    }
    return;
  }
  // A loaded filter is consistent: one more step and its read-outs must not crash (a
  // numerical failure on nonsense numbers is an exception, which is fine).
  try {
    const seif::Observation z{filter->landmarkIds().empty() ? 1 : filter->landmarkIds().front(),
                              seif::Vec2(1.0, 0.1), std::nullopt};
    filter->predict(seif::MotionIncrement{});
    filter->update(std::span<const seif::Observation>(&z, 1));
    (void)filter->mean();
    (void)filter->stats();
    (void)filter->poseCovariance();
  } catch (const std::exception&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  loadOrAbort(bytes);
  loadOrAbort(resealed(bytes));
  return 0;
}
