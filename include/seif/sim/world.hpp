#pragma once
// The simulator: a world of point landmarks, a robot that follows a closed (or straight)
// reference path with noisy velocity controls, and a range-bearing sensor. It produces the
// RobotLog a real robot would have logged (io/dataset.hpp), so simulated and recorded data
// take the same road to the filters. Worlds, paths, controller and noise: docs/simulator.md.
//
// Everything random comes from one std::mt19937_64 seeded with WorldConfig::seed and drawn
// in a fixed order (landmarks, then per step: motion noise, then per landmark in range in
// subject order its detection draw (only when detection_probability < 1) and, if detected,
// its measurement noise, then (only when clutter > 0) the number of false detections and
// each one's range and bearing), so one config gives a bit-identical log; the defaults draw
// nothing for clutter or missed detections.
#include <seif/core/types.hpp>
#include <seif/core/dataset.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace seif {

/// The worlds the simulator knows (docs/simulator.md "Presets").
enum class WorldPreset {
  Paper,     ///< Thrun et al. 2002: landmarks uniform in the unit square (path: PaperPath)
  Uniform,   ///< the paper's density and sensor in a square of side sqrt(N / 50), lawnmower loop
  Corridor,  ///< a straight strip at the paper's density, driven once: the map grows steadily
  /// An outdoor park like Victoria Park: trees uniform in a square (150 by default, one per
  /// 400 m^2: about 245 m a side), a vehicle at 3 m/s on a lawnmower loop, a laser-like
  /// range-bearing sensor of 30 m (1 m blind zone), 4 Hz, noise like Victoria Park's
  /// (range 0.5 m, bearing 2 deg; speed 0.16 m/s and turn rate 0.012 rad/s per step).
  Park,
};

/// "paper" | "uniform" | "corridor" | "park". Throws InvalidArgument naming the valid names.
WorldPreset parseWorldPreset(std::string_view name);

/// The preset's lower-case name, as parseWorldPreset() accepts it.
std::string_view worldPresetName(WorldPreset preset);

/// The path the robot follows in the Paper world (the paper does not give its path;
/// docs/simulator.md "paper" compares the two).
enum class PaperPath {
  Lawnmower,  ///< closed boustrophedon survey of the square, 1.75 laps in 500 steps (default)
  Lissajous,  ///< 3:2 Lissajous curve crossing itself at wide angles, 1.6 laps in 500 steps
};

/// "lawnmower" | "lissajous". Throws InvalidArgument naming the valid names.
PaperPath parsePaperPath(std::string_view name);

/// The path's lower-case name, as parsePaperPath() accepts it.
std::string_view paperPathName(PaperPath path);

/// Everything that defines a simulated run. Get one from presetConfig() and change fields
/// if needed; simulate() validates it. Units: metres, seconds, radians.
struct WorldConfig {
  WorldPreset preset = WorldPreset::Paper;
  PaperPath paper_path = PaperPath::Lawnmower;  ///< the Paper world's path (others ignore it)
  int landmarks = 50;        ///< number of landmarks N (subjects 6 .. 5 + N)
  int steps = 500;           ///< number of control steps T
  std::uint64_t seed = 1;    ///< the one seed of all randomness
  NoiseModel noise;          ///< true control and measurement noise (standard deviations)
  double sensor_range = 0.2;  ///< omnidirectional sensor: landmarks within this range are seen
  /// Blind zone: landmarks closer than this are not reported. The presets use 0.05 (about one
  /// range sigma): nearer detections have a range no better than its noise, a bearing whose
  /// linearisation fails, and made the reference EKF inconsistent (docs/simulator.md).
  double min_range = 0.0;
  double dt = 1.0;           ///< control period [s]
  double speed = 0.02;       ///< nominal forward speed along the reference path [m/s]
  /// Landmarks per square unit. Sizes the Uniform square (side sqrt(N / density)) and the
  /// Corridor (length N / (density * corridor_width)); the Paper square is always [0, 1]^2.
  double density = 50.0;
  double corridor_width = 0.4;  ///< width of the Corridor strip, centred on its axis
  /// Mean number of false detections per scan (Poisson), uniform over the sensor's footprint:
  /// area-uniform between the blind zone (min_range) and sensor_range, bearing uniform over
  /// the field of view (all around). Logged with subject kClutterSubject (core/dataset.hpp):
  /// observations of no landmark, which a filter with known association refuses.
  double clutter = 0.0;
  /// Probability that a landmark in range is reported (independently per landmark and scan).
  double detection_probability = 1.0;
};

/// The preset's configuration with N = `landmarks` and T = `steps`; a value <= 0 selects
/// the preset's default (Paper: 50 landmarks, 500 steps; Uniform: 500 landmarks, at least
/// 500 steps and enough for one lap of the loop; Corridor: 1000 landmarks, enough steps to
/// drive past all of them). The defaults of T depend on N, so pass N here rather than
/// changing `landmarks` afterwards.
WorldConfig presetConfig(WorldPreset preset, int landmarks = 0, int steps = 0,
                         std::uint64_t seed = 1);

/// What a run cost and what it saw (all counts over the whole run).
struct SimStats {
  /// Largest number of landmarks whose distance was computed in one step: the spatial
  /// index makes this independent of N at constant density.
  std::size_t candidates_checked_max_per_step = 0;
  std::size_t candidates_checked_total = 0;
  std::size_t measurements = 0;             ///< detections logged (clutter included)
  double mean_detections_per_step = 0.0;    ///< measurements / steps
  std::size_t max_detections_per_step = 0;
  std::size_t steps_without_detection = 0;
  std::size_t distinct_landmarks_seen = 0;  ///< landmarks detected at least once
  /// Detections dropped because the noisy range came out below the blind zone (the same
  /// threshold as for the true range): the sensor reports nothing there.
  std::size_t ranges_below_minimum = 0;
  std::size_t missed_detections = 0;  ///< landmarks in range not reported (detection_probability)
  std::size_t clutter = 0;            ///< false detections logged (included in measurements)
  /// Largest distance between the true position and the reference point the controller
  /// tracks: how far the noisy robot strayed from its path.
  double max_tracking_error = 0.0;
};

/// Runs the simulation (docs/simulator.md). Throws InvalidArgument for an invalid
/// config (landmarks < 1, steps < 1, non-positive or non-finite sensor_range, dt, speed,
/// density or corridor_width, negative or non-finite noise sigmas, clutter negative or not
/// finite, detection_probability outside [0, 1]). Fills `stats` if given.
RobotLog simulate(const WorldConfig& config, SimStats* stats = nullptr);

}  // namespace seif
