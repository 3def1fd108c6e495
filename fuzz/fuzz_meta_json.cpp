// libFuzzer target: meta.json alone (seif::readMetaJson). An input must give a valid noise
// (or none) or a DataError whose message is printable; anything else aborts (a finding).
#include "fuzz_support.hpp"

#include <seif/core/errors.hpp>

#include <cstdint>
#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  try {
    const auto noise = seif::readMetaJson(input, "meta.json");
    if (noise && !seif::fuzz::isValidNoise(*noise)) std::abort();
  } catch (const seif::DataError& e) {
    if (!seif::fuzz::isPrintable(e.what())) std::abort();
  }
  return 0;
}
