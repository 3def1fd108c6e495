#pragma once
// A RobotLog held in memory (the simulator's output, or a log read whole) as an
// EventSource: the same events an MRCLAM folder yields, so simulated and recorded data take
// the same road to the filters. Velocity model and range-bearing sensor from `noise`
// (per-step form: the simulator draws its noise once per control step).
#include <seif/io/event_source.hpp>

namespace seif {

class RobotLogSource final : public EventSource {
 public:
  /// `log` must outlive the source.
  RobotLogSource(const RobotLog& log, const NoiseModel& noise, NoiseForm form = NoiseForm::PerStep);

  const DatasetInfo& info() const override { return info_; }
  bool next(Event& event) override;
  double progress() const override;
  std::map<std::string, std::size_t> dropped() const override;

 private:
  const RobotLog& log_;
  DatasetInfo info_;
  std::size_t odometry_ = 0, measurement_ = 0, groundtruth_ = 0;
};

}  // namespace seif
