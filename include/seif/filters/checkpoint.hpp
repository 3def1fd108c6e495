#pragma once
// Checkpoints (docs/checkpoints.md): a filter's whole state in a versioned binary file,
// loadable without the caller re-supplying anything. The file holds the filter kind, its
// FilterConfig and SeifOptions, its motion and sensor models (VelocityModel, AckermannModel,
// OdometryModel; RangeBearingModel, CartesianModel, with noise and mount) and its state:
// means, the information store in its own order, active set, first estimates, counters and
// random state. A filter loaded from a checkpoint continues bit-identically to the one that
// was saved (same build, same inputs).
//
// EKF, EIF and SEIF (either sparsification) are supported; the batch MAP smoother
// (filter=batch) is not: saving it throws InvalidArgument. So does a filter whose
// models are not the library's own.
//
// Reading a truncated, corrupted, foreign or newer-format file throws seif::DataError
// naming the file and the byte offset, never anything else.
#include <seif/filters/slam_filter.hpp>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <string_view>

namespace seif {

/// The run loop's opaque resume position, stored with the filter and returned by load():
/// how many input steps the filter has consumed, and free-form key/value pairs (e.g. the
/// dataset, the spec, the next event's time, as text). The library never interprets them.
struct CheckpointExtras {
  std::uint64_t steps_consumed = 0;
  std::map<std::string, std::string> values;
  bool operator==(const CheckpointExtras&) const = default;
};

/// The checkpoint of `filter` as bytes (what saveCheckpoint() writes). Throws
/// InvalidArgument for a filter or model that cannot be checkpointed.
std::string saveToBytes(const SlamFilter& filter, const CheckpointExtras& extras = {});

/// Writes the checkpoint of `filter` to `path` atomically (complete or absent). Throws
/// InvalidArgument as saveToBytes(), DataError when the file cannot be written.
/// The same as filter.save(path, extras).
void saveCheckpoint(const SlamFilter& filter, const std::filesystem::path& path,
                    const CheckpointExtras& extras = {});

/// The filter stored in the checkpoint `path`; its resume position into `*extras` when
/// given. Throws DataError (naming the file) for anything but a valid checkpoint.
std::unique_ptr<SlamFilter> load(const std::filesystem::path& path, CheckpointExtras* extras = nullptr);

/// load() from bytes in memory; `name` names them in errors.
std::unique_ptr<SlamFilter> loadFromBytes(std::string_view bytes, const std::string& name,
                                          CheckpointExtras* extras = nullptr);

}  // namespace seif
