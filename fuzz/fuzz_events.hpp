#pragma once
// Shared by the event-source fuzz targets and their regression test: reads every event of a
// source and checks what every reader promises (finite values, time never going back,
// ranges > 0, finite positive-definite noise). A broken promise aborts (a finding).
#include <seif/core/errors.hpp>
#include <seif/io/event_source.hpp>

#include <Eigen/LU>

#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>
#include <variant>

namespace seif::fuzz {

/// The input split at the line "%%" into the named files, in order; the last takes the rest.
template <std::size_t N>
std::map<std::string, std::string, std::less<>> splitFiles(std::string_view input, const char* const (&names)[N]) {
  constexpr std::string_view kSep = "\n%%\n";
  std::map<std::string, std::string, std::less<>> files;
  for (std::size_t i = 0; i < N; ++i) {
    const std::size_t end = (i + 1 == N) ? std::string_view::npos : input.find(kSep);
    files.emplace(names[i], std::string(input.substr(0, end)));
    if (end == std::string_view::npos) break;
    input.remove_prefix(end + kSep.size());
  }
  return files;
}

/// The first promise an event breaks; empty when it keeps them all.
inline std::string brokenEvent(const Event& e, double previous_time) {
  const double t = eventTime(e);
  if (!std::isfinite(t)) return "non-finite time";
  if (t < previous_time) return "time goes back";
  if (const auto* c = std::get_if<ControlEvent>(&e)) {
    const bool finite = std::visit(
        [](const auto& u) {
          using U = std::decay_t<decltype(u)>;
          if constexpr (std::is_same_v<U, VelocityControl>) return std::isfinite(u.v) && std::isfinite(u.w);
          else if constexpr (std::is_same_v<U, AckermannControl>) return std::isfinite(u.speed) && std::isfinite(u.steering);
          else return u.delta.allFinite() && u.covariance.allFinite();
        },
        c->input);
    if (!finite) return "non-finite control";
  } else if (const auto* o = std::get_if<ObservationEvent>(&e)) {
    for (const Observation& z : o->observations) {
      if (!z.z.allFinite()) return "non-finite observation";
      if (z.noise && (!z.noise->allFinite() || !(z.noise->determinant() > 0.0))) return "bad observation noise";
    }
  } else if (const auto* g = std::get_if<GpsFix>(&e)) {
    if (!g->position.allFinite()) return "non-finite GPS";
  } else if (!std::get<TimedPose>(e).pose.allFinite()) {
    return "non-finite ground truth";
  }
  return {};
}

/// No control character or DEL in an error message (DataError escapes them).
inline bool printable(std::string_view message) {
  for (const char c : message) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x20 || b == 0x7F) return false;
  }
  return true;
}

/// Opens and drains a source; aborts on a broken promise or an exception other than a
/// printable DataError (seif::InvalidArgument from the options cannot happen: none given).
template <class Open>
void drainOrAbort(Open&& open) {
  try {
    auto source = open();
    Event e;
    double previous = -INFINITY;
    while (source->next(e)) {
      if (!brokenEvent(e, previous).empty()) std::abort();
      previous = eventTime(e);
    }
  } catch (const DataError& e) {
    if (!printable(e.what())) std::abort();
  }
}

}  // namespace seif::fuzz
