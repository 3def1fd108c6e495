// Readers (io/event_source.hpp: open_dataset, any format, streamed), the MRCLAM folder
// reader/writer, result files, and the simulator (sim/world.hpp).
#include "bindings.hpp"

#include <seif/io/event_source.hpp>
#include <seif/io/graph_file.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/io/results.hpp>
#include "io/robot_log_source.hpp"
#include "io/victoria_park.hpp"
#include <seif/sim/world.hpp>

namespace seif::python {
namespace {

void bindSources(py::module_& m) {
  py::class_<NoiseSetting>(m, "NoiseSetting", "One noise value a run uses and where it came from.")
      .def_readonly("name", &NoiseSetting::name)
      .def_readonly("value", &NoiseSetting::value)
      .def_readonly("unit", &NoiseSetting::unit)
      .def_readonly("source", &NoiseSetting::source)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"name", "value", "unit", "source"}); });

  py::class_<DatasetInfo>(m, "DatasetInfo",
                          "What a dataset says about itself: format, motion and sensor models, noise with "
                          "sources, start pose, ground-truth landmarks.")
      .def_readonly("source", &DatasetInfo::source)
      .def_readonly("format", &DatasetInfo::format)
      .def_property_readonly("motion", [](const DatasetInfo& i) { return std::const_pointer_cast<MotionModel>(i.motion); })
      .def_property_readonly("sensor",
                             [](const DatasetInfo& i) { return std::const_pointer_cast<MeasurementModel>(i.sensor); })
      .def_readonly("noise", &DatasetInfo::noise, py::return_value_policy::copy)
      .def_readonly("start_pose", &DatasetInfo::start_pose)
      .def_readonly("start_pose_source", &DatasetInfo::start_pose_source)
      .def_readonly("start_pose_id", &DatasetInfo::start_pose_id)
      .def_readonly("landmarks", &DatasetInfo::landmarks, py::return_value_policy::copy)
      .def_readonly("has_groundtruth", &DatasetInfo::has_groundtruth)
      .def_readonly("has_gps", &DatasetInfo::has_gps)
      .def("filter_config",
           [](const DatasetInfo& i) {
             FilterConfig c;
             c.motion = i.motion;
             c.sensor = i.sensor;
             return c;
           },
           "A FilterConfig with this dataset's motion and sensor models (as `seif run` builds it).")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"source", "format", "motion", "sensor", "start_pose"}); });

  bindNamedEnum<DatasetFormat>(m, "DatasetFormat",
                               "'auto' | 'mrclam' | 'victoria-park' | 'isam' | 'g2o'", &parseDatasetFormat,
                               &datasetFormatName)
      .value("Auto", DatasetFormat::Auto)
      .value("Mrclam", DatasetFormat::Mrclam)
      .value("VictoriaPark", DatasetFormat::VictoriaPark)
      .value("Isam", DatasetFormat::Isam)
      .value("G2o", DatasetFormat::G2o);

  bindNamedEnum<Detections>(m, "Detections", "'associated' | 'raw': the Victoria Park detections a reader gives",
                            &parseDetections, &detectionsName)
      .value("Associated", Detections::Associated)
      .value("Raw", Detections::Raw);

  py::class_<DatasetOptions>(m, "DatasetOptions", "What a reader opens with (io/event_source.hpp).")
      .def(py::init([](int robot, const std::map<std::string, double>& noise, const std::optional<NoiseForm>& form) {
             return DatasetOptions{robot, noise, form, false, Detections::Associated};
           }),
           py::arg("robot") = 1, py::arg("noise") = std::map<std::string, double>{},
           py::arg("noise_form") = py::none())
      .def_readwrite("robot", &DatasetOptions::robot, "MRCLAM: which robot's log")
      .def_readwrite("noise", &DatasetOptions::noise, "noise overrides by name, e.g. {'sigma_v': 0.05}")
      .def_readwrite("noise_form", &DatasetOptions::noise_form, "NoiseForm, or None for the format's default")
      .def_readwrite("isam_landmarks_as_gtsam", &DatasetOptions::isam_landmarks_as_gtsam,
                     "iSAM LANDMARK records read as GTSAM's loader does (bearing-range, its heuristic noise)")
      .def_readwrite("detections", &DatasetOptions::detections,
                     "Victoria Park: Detections.Associated (the UTS file) or Detections.Raw (tree_detections.txt, "
                     "landmark unknown, truth from the UTS file)")
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"robot", "noise", "noise_form", "isam_landmarks_as_gtsam", "detections"});
      });

  py::class_<EventSource>(m, "EventSource",
                          "A dataset streamed as time-ordered events: iterate it for ControlEvent, "
                          "ObservationEvent, TimedPose (ground truth) and GpsFix. Iterating consumes it "
                          "(open the dataset again to restart).")
      .def_property_readonly("info", &EventSource::info, py::return_value_policy::reference_internal)
      .def("progress", &EventSource::progress, "fraction of the input read so far")
      .def("dropped", &EventSource::dropped, "records dropped so far, by reason")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](EventSource& s) {
        Event e;
        if (!s.next(e)) throw py::stop_iteration();
        return e;
      });

  py::class_<RobotLogSource, EventSource>(m, "RobotLogSource",
                                          "A RobotLog in memory as an EventSource (the simulator's output); velocity "
                                          "model and range-bearing sensor from `noise`.")
      .def(py::init<const RobotLog&, const NoiseModel&, NoiseForm>(), py::arg("log"), py::arg("noise"),
           py::arg("form") = NoiseForm::PerStep, py::keep_alive<1, 2>());

  m.def(
      "open_dataset",
      [](const std::filesystem::path& path, DatasetFormat format, const std::optional<DatasetOptions>& options) {
        return openDataset(path, format, options.value_or(DatasetOptions{}));
      },
      py::arg("path"), py::arg("format") = DatasetFormat::Auto, py::arg("options") = py::none(),
      "Opens a dataset (MRCLAM folder, Victoria Park folder, iSAM or g2o file) as an EventSource; "
      "format 'auto' tells them apart. Raises DataError ('file:line: what') for bad input.");
  m.def("looks_like_victoria_park", &looksLikeVictoriaPark, py::arg("path"));
  bindNamedEnum<GraphFormat>(m, "GraphFormat", "'isam' | 'g2o'", &parseGraphFormat, &graphFormatName)
      .value("Isam", GraphFormat::Isam)
      .value("G2o", GraphFormat::G2o);
  m.def(
      "convert_dataset",
      [](const std::filesystem::path& input, const std::filesystem::path& output, GraphFormat to,
         DatasetFormat input_format) { convertDataset(input, input_format, output, to); },
      py::arg("input"), py::arg("output"), py::arg("to"), py::arg("input_format") = DatasetFormat::Auto,
      py::call_guard<py::gil_scoped_release>(),
        "`seif convert`: a dataset (an odometry stream with pose ids: iSAM or g2o) written as a graph file "
        "of format `to` (iSAM or g2o); DataError for anything else.");

  m.def("read_mrclam", py::overload_cast<const std::filesystem::path&, int>(&readMrclam), py::arg("dir"),
        py::arg("robot") = 1, "Reads one robot of an MRCLAM folder into a RobotLog.");
  m.def("write_mrclam", &writeMrclam, py::arg("dir"), py::arg("log"),
        "Writes a RobotLog as an MRCLAM folder (what `seif simulate` writes).");
  m.def("write_tum", &writeTum, py::arg("file"), py::arg("trajectory"), "Writes a list of TimedPose as TUM.");
  m.def(
      "write_map_csv",
      [](const std::filesystem::path& file, const SlamFilter& filter, bool covariances) { writeMapCsv(file, filter, covariances); },
      py::arg("file"), py::arg("filter"), py::arg("covariances") = true,
      "Writes a filter's map as map.csv (id,x,y[,cov_xx,cov_xy,cov_yy]); NumericError naming the landmark "
      "whose estimate or covariance is not finite, and nothing written.");
}

void bindSimulator(py::module_& m) {
  bindNamedEnum<WorldPreset>(m, "WorldPreset", "'paper' | 'uniform' | 'corridor' | 'park'", &parseWorldPreset,
                             &worldPresetName)
      .value("Paper", WorldPreset::Paper)
      .value("Uniform", WorldPreset::Uniform)
      .value("Corridor", WorldPreset::Corridor)
      .value("Park", WorldPreset::Park);
  bindNamedEnum<PaperPath>(m, "PaperPath", "'lawnmower' | 'lissajous'", &parsePaperPath, &paperPathName)
      .value("Lawnmower", PaperPath::Lawnmower)
      .value("Lissajous", PaperPath::Lissajous);

  py::class_<WorldConfig>(m, "WorldConfig",
                          "Everything that defines a simulated run (sim/world.hpp); get one from preset_config().")
      .def(py::init<>())
      .def_readwrite("preset", &WorldConfig::preset)
      .def_readwrite("paper_path", &WorldConfig::paper_path)
      .def_readwrite("landmarks", &WorldConfig::landmarks)
      .def_readwrite("steps", &WorldConfig::steps)
      .def_readwrite("seed", &WorldConfig::seed)
      .def_readwrite("noise", &WorldConfig::noise)
      .def_readwrite("sensor_range", &WorldConfig::sensor_range)
      .def_readwrite("min_range", &WorldConfig::min_range)
      .def_readwrite("dt", &WorldConfig::dt)
      .def_readwrite("speed", &WorldConfig::speed)
      .def_readwrite("density", &WorldConfig::density)
      .def_readwrite("corridor_width", &WorldConfig::corridor_width)
      .def_readwrite("clutter", &WorldConfig::clutter,
                     "mean false detections per scan (Poisson, uniform in the footprint; subject CLUTTER_SUBJECT)")
      .def_readwrite("detection_probability", &WorldConfig::detection_probability,
                     "probability that a landmark in range is reported")
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"preset", "paper_path", "landmarks", "steps", "seed", "noise", "sensor_range", "min_range",
                          "dt", "speed", "density", "corridor_width", "clutter", "detection_probability"});
      });
  m.def("preset_config", &presetConfig, py::arg("preset") = WorldPreset::Paper, py::arg("landmarks") = 0,
        py::arg("steps") = 0, py::arg("seed") = 1,
        "A preset's WorldConfig; landmarks / steps <= 0 select the preset's defaults.");

  py::class_<SimStats>(m, "SimStats", "What a simulated run cost and saw.")
      .def_readonly("candidates_checked_max_per_step", &SimStats::candidates_checked_max_per_step)
      .def_readonly("candidates_checked_total", &SimStats::candidates_checked_total)
      .def_readonly("measurements", &SimStats::measurements)
      .def_readonly("mean_detections_per_step", &SimStats::mean_detections_per_step)
      .def_readonly("max_detections_per_step", &SimStats::max_detections_per_step)
      .def_readonly("steps_without_detection", &SimStats::steps_without_detection)
      .def_readonly("distinct_landmarks_seen", &SimStats::distinct_landmarks_seen)
      .def_readonly("ranges_below_minimum", &SimStats::ranges_below_minimum)
      .def_readonly("missed_detections", &SimStats::missed_detections)
      .def_readonly("clutter", &SimStats::clutter)
      .def_readonly("max_tracking_error", &SimStats::max_tracking_error);

  m.def(
      "simulate", [](const WorldConfig& c) { return simulate(c); }, py::arg("config"),
      py::call_guard<py::gil_scoped_release>(),
      "Runs the simulator: a RobotLog (bit-identical for one config). Raises InvalidArgument for a bad config.");
  m.def(
      "simulate_with_stats",
      [](const WorldConfig& c) {
        SimStats stats;
        RobotLog log;
        {
          py::gil_scoped_release release;
          log = simulate(c, &stats);
        }
        return py::make_tuple(std::move(log), stats);
      },
      py::arg("config"), "simulate() and its SimStats: (log, stats).");
}

}  // namespace

void bindIo(py::module_& m) {
  bindSources(m);
  bindSimulator(m);
}

}  // namespace seif::python
