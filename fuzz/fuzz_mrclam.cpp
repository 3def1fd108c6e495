// libFuzzer target: the whole MRCLAM reader, from memory (input format: fuzz_support.hpp).
// An input must be read into a log with the documented properties or be rejected with a
// DataError whose message is printable; anything else aborts (a finding).
#include "fuzz_support.hpp"

#include <seif/core/errors.hpp>

#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    const seif::RobotLog log =
        seif::readMrclam(seif::fuzz::splitMrclamInput(input), seif::fuzz::kRobot);
    if (!seif::fuzz::brokenInvariant(log).empty()) std::abort();
  } catch (const seif::DataError& e) {
    if (!seif::fuzz::isPrintable(e.what())) std::abort();
  }
  return 0;
}
