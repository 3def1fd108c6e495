// libFuzzer target: checkpoints from memory (seif::loadFromBytes) and the associator state
// a run's checkpoint carries (seif::Associator::restoreState). Each input is read twice: as
// it is, and with its header's payload size and checksum made to match (so that the fuzzer
// reaches the payload's parser, not only the checksum). Either must load or throw
// seif::DataError with a printable message; a loaded filter must then take a step, and a
// restored associator must save the bytes it restores to.
#include "fuzz_checkpoint.hpp"
#include "fuzz_support.hpp"

#include <seif/association/association.hpp>
#include <seif/core/errors.hpp>
#include <seif/filters/checkpoint.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

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

void restoreOrAbort(const std::string& bytes) {
  std::string saved;
  try {
    saved = seif::Associator::restoreState(bytes, "fuzz").saveState();
  } catch (const seif::DataError& e) {
    if (!seif::fuzz::isPrintable(e.what())) {
      std::fprintf(stderr, "unprintable DataError message\n");
      std::abort();
    }
    return;
  }
  if (seif::Associator::restoreState(saved, "fuzz").saveState() != saved) {
    std::fprintf(stderr, "a restored associator does not save what it restores\n");
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  loadOrAbort(bytes);
  loadOrAbort(seif::fuzz::resealed(bytes));
  restoreOrAbort(bytes);
  restoreOrAbort(seif::fuzz::resealed(bytes));
  return 0;
}
