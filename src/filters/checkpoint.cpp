// Checkpoints (include/seif/filters/checkpoint.hpp, docs/checkpoints.md): the container,
// the filter kind, the configuration and the models; each filter's state is in its own
// file (checkpoint_access.hpp).
#include "checkpoint_access.hpp"

#include "models/model_io.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/checkpoint.hpp>
#include "core/files.hpp"

#include <limits>
#include <stdexcept>

namespace seif {

namespace {

// An option's range is its constructor's (construct(): the option table's); here an int.
constexpr std::int64_t kIntMin = std::numeric_limits<int>::min();
constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();

void writeExtras(ArchiveWriter& out, const CheckpointExtras& extras) {
  out.section("extras");
  out.u64(extras.steps_consumed);
  out.count(extras.values.size());
  for (const auto& [key, value] : extras.values) {
    out.str(key);
    out.str(value);
  }
}

CheckpointExtras readExtras(ArchiveReader& in) {
  in.section("extras");
  CheckpointExtras extras;
  extras.steps_consumed = in.u64("steps consumed");
  const std::size_t n = in.count("extras count", 18);
  for (std::size_t i = 0; i < n; ++i) {
    std::string key = in.str("extras key");
    std::string value = in.str("extras value");
    if (!extras.values.emplace(std::move(key), std::move(value)).second) in.fail("an extras key stored twice");
  }
  return extras;
}

// FilterConfig without its models (written separately).
void writeConfig(ArchiveWriter& out, const FilterConfig& c) {
  out.section("config");
  out.fixed(c.initial_pose_sigma);
  out.f64(c.outlier_gate);
  out.u64(static_cast<std::uint64_t>(c.linearization));
  out.u64(static_cast<std::uint64_t>(c.iterations));
}

FilterConfig readConfig(ArchiveReader& in) {
  in.section("config");
  FilterConfig c;
  if (in.version() == 1) {  // version 1 held the sigmas of the default models, now always stored as models
    for (const char* name : {"sigma_v", "sigma_w", "sigma_range", "sigma_bearing"}) (void)in.f64(name);
  }
  in.fixed("initial pose sigma", c.initial_pose_sigma);
  c.outlier_gate = in.f64("outlier gate");
  c.linearization = static_cast<Linearization>(in.u64Max("linearization", in.version() == 1 ? 1 : 3));
  if (in.version() >= 2) c.iterations = static_cast<int>(in.u64Max("iterations", kIntMax));
  return c;
}

void writeSeifOptions(ArchiveWriter& out, const SeifOptions& o) {
  out.section("seif-options");
  out.i64(o.active);
  out.i64(o.relax);
  out.u64(static_cast<std::uint64_t>(o.mean));
  out.u64(static_cast<std::uint64_t>(o.deactivate));
  out.u64(static_cast<std::uint64_t>(o.recovery));
  out.u64(static_cast<std::uint64_t>(o.relax_order));
  out.u64(o.seed);
  out.u64(static_cast<std::uint64_t>(o.sparsify));
  out.u64(static_cast<std::uint64_t>(o.covariance));
  out.i64(o.beta);
  out.f64(o.reanchor);
  out.i64(o.blanket);
  out.u64(o.bounds ? 1 : 0);
  out.u64(static_cast<std::uint64_t>(o.motion));
  out.f64(o.rho);
  out.u64(static_cast<std::uint64_t>(o.gauge));
  out.u64(static_cast<std::uint64_t>(o.coarse));
  out.i64(o.stale);
  out.f64(o.omega);
  out.f64(o.wildfire);
}

SeifOptions readSeifOptions(ArchiveReader& in) {
  in.section("seif-options");
  SeifOptions o;
  o.active = static_cast<int>(in.i64In("active", kIntMin, kIntMax));
  o.relax = static_cast<int>(in.i64In("relax", kIntMin, kIntMax));
  o.mean = static_cast<SeifOptions::Mean>(in.u64Max("mean", 1));
  o.deactivate = static_cast<SeifOptions::Deactivate>(in.u64Max("deactivate", 1));
  o.recovery = static_cast<SeifOptions::Recovery>(in.u64Max("recovery", 1));
  o.relax_order = static_cast<SeifOptions::RelaxOrder>(in.u64Max("relax order", in.version() >= 13 ? 2 : 1));
  o.seed = in.u64("seed");
  o.sparsify = static_cast<SeifOptions::Sparsify>(in.u64Max("sparsify", in.version() >= 6 ? 2 : 1));
  o.covariance = static_cast<SeifOptions::Covariance>(in.u64Max("covariance", in.version() >= 4 ? 2 : 1));
  o.beta = static_cast<int>(in.i64In("beta", kIntMin, kIntMax));
  if (in.version() >= 2) o.reanchor = in.f64("reanchor");
  // Version 2 had no bound: its local marginals used the whole Markov blanket.
  o.blanket = in.version() >= 3 ? static_cast<int>(in.i64In("blanket", kIntMin, kIntMax)) : 0;
  o.bounds = in.version() >= 4 && in.u64Max("bounds", 1) == 1;  // earlier files kept none
  if (in.version() >= 5) o.motion = static_cast<SeifOptions::Motion>(in.u64Max("motion", 1));
  if (in.version() >= 6) o.rho = in.f64("rho");
  if (in.version() >= 7) o.gauge = static_cast<SeifOptions::Gauge>(in.u64Max("gauge", 1));
  if (in.version() >= 8) o.coarse = static_cast<SeifOptions::Coarse>(in.u64Max("coarse", 1));
  if (in.version() >= 11) o.stale = in.i64("stale");  // earlier files: off
  if (in.version() >= 12) o.omega = in.f64("omega");  // earlier files: eq. (42) as published
  if (in.version() >= 13) o.wildfire = in.f64("wildfire");
  return o;
}

template <class Filter>
void writeFilter(ArchiveWriter& out, const Filter& f, const char* kind) {
  out.str(kind);
  writeConfig(out, CheckpointAccess::config(f));
  writeMotionModel(out, f.motionModel());
  writeSensorModel(out, f.sensorModel());
}

/// Constructs a filter from the stored configuration; a refusal is a DataError.
template <class Make>
std::unique_ptr<SlamFilter> construct(ArchiveReader& in, Make make) {
  try {
    return make();
  } catch (const InvalidArgument& e) {
    in.fail(std::string("invalid filter configuration: ") + e.what());
  }
}

}  // namespace

std::string saveToBytes(const SlamFilter& filter, const CheckpointExtras& extras) {
  ArchiveWriter out;
  out.section("seif-checkpoint");
  if (const auto* ekf = dynamic_cast<const EkfSlam*>(&filter)) {
    writeFilter(out, *ekf, "ekf");
    writeExtras(out, extras);
    CheckpointAccess::write(out, *ekf);
  } else if (const auto* eif = dynamic_cast<const EifSlam*>(&filter)) {
    writeFilter(out, *eif, "eif");
    writeExtras(out, extras);
    CheckpointAccess::write(out, *eif);
  } else if (const auto* seif = dynamic_cast<const SeifSlam*>(&filter)) {
    writeFilter(out, *seif, "seif");
    writeSeifOptions(out, seif->options());
    writeExtras(out, extras);
    CheckpointAccess::write(out, *seif);
  } else {
    throw InvalidArgument("checkpoint: the " + filter.name() +
                                (filter.smoother() ? " smoother (filter=batch) keeps every input until finish() and "
                                                     "cannot be checkpointed"
                                                   : " filter cannot be checkpointed") +
                                " (ekf, eif and seif can)");
  }
  out.section("end");
  return out.bytes();
}

void saveCheckpoint(const SlamFilter& filter, const std::filesystem::path& path, const CheckpointExtras& extras) {
  writeFileAtomically(path, saveToBytes(filter, extras));
}

void SlamFilter::save(const std::filesystem::path& path) const { saveCheckpoint(*this, path); }

void SlamFilter::save(const std::filesystem::path& path, const CheckpointExtras& extras) const {
  saveCheckpoint(*this, path, extras);
}

std::unique_ptr<SlamFilter> loadFromBytes(std::string_view bytes, const std::string& name, CheckpointExtras* extras) {
  ArchiveReader in(bytes, name);
  in.section("seif-checkpoint");
  const std::string kind = in.str("filter kind");
  if (kind != "ekf" && kind != "eif" && kind != "seif") in.fail("unknown filter kind '" + kind + "'");
  FilterConfig config = readConfig(in);
  config.motion = readMotionModel(in);
  config.sensor = readSensorModel(in);
  const SeifOptions options = kind == "seif" ? readSeifOptions(in) : SeifOptions{};
  CheckpointExtras stored = readExtras(in);
  std::unique_ptr<SlamFilter> filter;
  if (kind == "ekf") {
    auto ekf = construct(in, [&] { return std::make_unique<EkfSlam>(Pose2::Zero(), config); });
    CheckpointAccess::read(in, static_cast<EkfSlam&>(*ekf));
    filter = std::move(ekf);
  } else if (kind == "eif") {
    auto eif = construct(in, [&] { return std::make_unique<EifSlam>(Pose2::Zero(), config); });
    CheckpointAccess::read(in, static_cast<EifSlam&>(*eif));
    filter = std::move(eif);
  } else {
    auto seif = construct(in, [&] { return std::make_unique<SeifSlam>(Pose2::Zero(), config, options); });
    CheckpointAccess::read(in, static_cast<SeifSlam&>(*seif));
    filter = std::move(seif);
  }
  in.section("end");
  in.finish();
  if (extras) *extras = std::move(stored);
  return filter;
}

std::unique_ptr<SlamFilter> load(const std::filesystem::path& path, CheckpointExtras* extras) {
  const std::optional<std::string> bytes = readFileIfExists(path);
  if (!bytes) throw DataError(path.string(), 0, "checkpoint file not found");
  return loadFromBytes(*bytes, path.string(), extras);
}

}  // namespace seif
