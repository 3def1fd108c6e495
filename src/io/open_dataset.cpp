// openDataset(): interim, until the streaming readers land.
#include <seif/core/errors.hpp>
#include <seif/io/event_source.hpp>
#include <seif/io/graph_file.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/io/robot_log_source.hpp>
#include <seif/io/victoria_park.hpp>

namespace seif {
namespace {
class OwningLogSource final : public EventSource {
 public:
  explicit OwningLogSource(RobotLog log, const NoiseModel& n) : log_(std::move(log)), source_(log_, n) {}
  const DatasetInfo& info() const override { return source_.info(); }
  bool next(Event& e) override { return source_.next(e); }
  double progress() const override { return source_.progress(); }
  std::map<std::string, std::size_t> dropped() const override { return source_.dropped(); }

 private:
  RobotLog log_;
  RobotLogSource source_;
};
}  // namespace

std::unique_ptr<EventSource> openDataset(const std::filesystem::path& path, DatasetFormat format, const DatasetOptions& options) {
  if (format == DatasetFormat::VictoriaPark || (format == DatasetFormat::Auto && looksLikeVictoriaPark(path))) {
    return openVictoriaPark(path, options);
  }
  if (format == DatasetFormat::Isam || (format == DatasetFormat::Auto && looksLikeIsam(path))) return openIsam(path, options);
  if (format == DatasetFormat::G2o || (format == DatasetFormat::Auto && looksLikeG2o(path))) return openG2o(path, options);
  RobotLog log = readMrclam(path, options.robot);
  const NoiseModel n = log.noise.value_or(NoiseModel{0.05, 0.2, 0.2, 0.03});
  return std::make_unique<OwningLogSource>(std::move(log), n);
}

void convertDataset(const std::filesystem::path& in, DatasetFormat in_format, const std::filesystem::path& out,
                    GraphFormat to) {
  auto source = openDataset(in, in_format);
  writeGraph(out, *source, to);
}

}  // namespace seif
