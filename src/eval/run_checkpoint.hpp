#pragma once
// Checkpoints of a streamed run (eval/run.hpp RunCheckpointing, RunResume): the observer
// that saves them, and the run's outputs so far in the checkpoint's extras.
#include <seif/association/association.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>

#include <string>
#include <string_view>

namespace seif {

/// Saves the filter and `out` (kept up to date by the observers before it) after every
/// `every`-th step and where a stopped run stops, as a checkpoint whose extras say how many
/// steps were consumed.
class CheckpointWriter : public RunObserver {
 public:
  /// With `associator`, its state is saved beside the filter (kAssociatorKey); with
  /// `digest`, the digest of the steps consumed (kStepsDigestKey).
  CheckpointWriter(const RunCheckpointing& policy, const RunOutput& out, const Associator* associator = nullptr,
                   const StepDigest* digest = nullptr)
      : policy_(policy), out_(out), associator_(associator), digest_(digest) {}
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override;
  void onStop(const SlamFilter& filter, std::size_t steps) override { save(filter, steps); }

 private:
  void save(const SlamFilter& filter, std::size_t steps) const;

  const RunCheckpointing& policy_;
  const RunOutput& out_;
  const Associator* associator_;
  const StepDigest* digest_;
};


std::string encodeRunOutput(const RunOutput& out);
/// Throws DataError naming `name` for bytes encodeRunOutput() did not write.
RunOutput decodeRunOutput(std::string_view bytes, const std::string& name);

/// RunOutput::associations and merges (kRunAssociationsKey).
std::string encodeRunAssociations(const RunOutput& out);
/// Into `out`, whose `steps` they must lie within. Throws DataError naming `name` for bytes
/// encodeRunAssociations() did not write.
void decodeRunAssociations(std::string_view bytes, const std::string& name, RunOutput& out);

}  // namespace seif
