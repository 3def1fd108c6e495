// Core vocabulary (core/types.hpp, core/dataset.hpp) and the models (models/*.hpp).
// Pose2 (x, y, theta), Vec2 and the matrices are numpy arrays (float64) both ways.
#include "bindings.hpp"

#include <seif/core/angles.hpp>
#include <seif/core/dataset.hpp>
#include <seif/core/types.hpp>
#include <seif/models/ackermann_model.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_model.hpp>
#include "models/velocity_motion.hpp"

namespace seif::python {

void bindCore(py::module_& m) {
  // --- inputs and observations ----------------------------------------------------------
  py::class_<VelocityControl>(m, "VelocityControl",
                              "Velocity-model control: forward speed v [m/s], turn rate w [rad/s], for dt [s].")
      .def(py::init([](double v, double w, double dt) { return VelocityControl{v, w, dt}; }),
           py::arg("v") = 0.0, py::arg("w") = 0.0, py::arg("dt") = 0.0)
      .def_readwrite("v", &VelocityControl::v)
      .def_readwrite("w", &VelocityControl::w)
      .def_readwrite("dt", &VelocityControl::dt)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"v", "w", "dt"}); });

  py::class_<AckermannControl>(m, "AckermannControl",
                               "Car-like control: encoder speed [m/s], front-wheel steering angle "
                               "[rad, left positive], for dt [s].")
      .def(py::init([](double speed, double steering, double dt) { return AckermannControl{speed, steering, dt}; }),
           py::arg("speed") = 0.0, py::arg("steering") = 0.0, py::arg("dt") = 0.0)
      .def_readwrite("speed", &AckermannControl::speed)
      .def_readwrite("steering", &AckermannControl::steering)
      .def_readwrite("dt", &AckermannControl::dt)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"speed", "steering", "dt"}); });

  py::class_<OdometryIncrement>(m, "OdometryIncrement",
                                "Relative odometry: the next pose in the current one's frame (dx, dy, dth) "
                                "with its 3x3 covariance.")
      .def(py::init([](const Vec3& delta, const Mat3& covariance) { return OdometryIncrement{delta, covariance}; }),
           py::arg("delta") = Vec3::Zero().eval(), py::arg("covariance") = Mat3::Identity().eval())
      .def_readwrite("delta", &OdometryIncrement::delta)
      .def_readwrite("covariance", &OdometryIncrement::covariance)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"delta", "covariance"}); });

  m.attr("UNKNOWN_LANDMARK") = kUnknownLandmark;
  py::class_<Observation>(m, "Observation",
                          "One observation z of landmark `landmark` in the sensor's units (range-bearing: "
                          "(range [m], bearing [rad]); Cartesian: (x, y) [m]), with its own 2x2 noise or "
                          "None for the sensor's default.")
      .def(py::init([](int landmark, const Vec2& z, const std::optional<Mat2>& noise) {
             return Observation{landmark, z, noise};
           }),
           py::arg("landmark"), py::arg("z"), py::arg("noise") = py::none())
      .def_readwrite("landmark", &Observation::landmark)
      .def_readwrite("z", &Observation::z)
      .def_readwrite("noise", &Observation::noise, py::return_value_policy::copy)
      .def_readwrite("truth", &Observation::truth,
                     "the id the data names for what was seen, to score an association only (UNKNOWN_LANDMARK: none)")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"landmark", "z", "noise", "truth"}); });

  py::class_<NoiseModel>(m, "NoiseModel", "Standard deviations of control and measurement noise.")
      .def(py::init([](double sv, double sw, double sr, double sb) { return NoiseModel{sv, sw, sr, sb}; }),
           py::arg("sigma_v") = NoiseModel{}.sigma_v, py::arg("sigma_w") = NoiseModel{}.sigma_w,
           py::arg("sigma_range") = NoiseModel{}.sigma_range, py::arg("sigma_bearing") = NoiseModel{}.sigma_bearing)
      .def_readwrite("sigma_v", &NoiseModel::sigma_v, "forward velocity [m/s]")
      .def_readwrite("sigma_w", &NoiseModel::sigma_w, "rotational velocity [rad/s]")
      .def_readwrite("sigma_range", &NoiseModel::sigma_range, "[m]")
      .def_readwrite("sigma_bearing", &NoiseModel::sigma_bearing, "[rad]")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"sigma_v", "sigma_w", "sigma_range", "sigma_bearing"}); });

  m.def("wrap_angle", &wrapAngle, py::arg("angle"), "The angle wrapped to (-pi, pi].");

  // --- motion models ----------------------------------------------------------------------
  py::class_<MotionIncrement>(m, "MotionIncrement",
                              "A linearised motion: pose increment delta, its Jacobian J_delta_x = dDelta/dx "
                              "and the process noise U (3x3, pose space). What filter.predict() consumes.")
      .def(py::init([](const Vec3& delta, const Mat3& J, const Mat3& U) { return MotionIncrement{delta, J, U}; }),
           py::arg("delta") = Vec3::Zero().eval(), py::arg("J_delta_x") = Mat3::Zero().eval(),
           py::arg("U") = Mat3::Zero().eval())
      .def_readwrite("delta", &MotionIncrement::delta)
      .def_readwrite("J_delta_x", &MotionIncrement::J_delta_x)
      .def_readwrite("U", &MotionIncrement::U)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"delta", "J_delta_x", "U"}); });

  bindNamedEnum<NoiseForm>(m, "NoiseForm",
                           "Form of a rate-driven model's noise: PerStep (the paper's, per control step) or "
                           "Rate (noise densities, U grows like dt). Strings 'per-step' | 'rate' are accepted.",
                           &parseNoiseForm, &noiseFormName)
      .value("PerStep", NoiseForm::PerStep)
      .value("Rate", NoiseForm::Rate);

  py::class_<MotionModel, std::shared_ptr<MotionModel>>(
      m, "MotionModel", "A vehicle's motion model: linearises an input at a pose (abstract).")
      .def("describe", &MotionModel::describe, "One line with the parameters.")
      .def("linearize", py::overload_cast<const Pose2&, const MotionInput&>(&MotionModel::linearize, py::const_),
           py::arg("x"), py::arg("u"),
           "The MotionIncrement of input u at pose x. Raises InvalidArgument for an input of "
           "another model or a non-finite one.")
      .def("apply", &MotionModel::apply, py::arg("x"), py::arg("u"),
           "Dead reckoning: x + Delta(x, u), heading wrapped.")
      .def("__repr__", [](const MotionModel& mm) { return "<" + mm.describe() + ">"; });

  py::class_<VelocityModel, MotionModel, std::shared_ptr<VelocityModel>>(
      m, "VelocityModel", "Velocity (v, w) motion model with control noise diag(sigma_v^2, sigma_w^2).")
      .def(py::init<double, double, NoiseForm>(), py::arg("sigma_v"), py::arg("sigma_w"),
           py::arg("form") = NoiseForm::PerStep)
      .def_property_readonly("sigma_v", &VelocityModel::sigmaV)
      .def_property_readonly("sigma_w", &VelocityModel::sigmaW)
      .def_property_readonly("form", &VelocityModel::form);

  m.def(
      "velocity_delta",
      [](const Pose2& x, const VelocityControl& u) {
        Mat3 J_x;
        Mat32 J_u;
        const Vec3 d = VelocityMotionModel::delta(x, u, &J_x, &J_u);
        return py::make_tuple(d, J_x, J_u);
      },
      py::arg("x"), py::arg("u"),
      "The velocity model's exact pose increment and its Jacobians: (delta, dDelta/dx (3x3), "
      "dDelta/d(v, w) (3x2)).");

  py::class_<AckermannGeometry>(m, "AckermannGeometry", "Car-like vehicle geometry.")
      .def(py::init([](double L, double H, const Vec2& p) { return AckermannGeometry{L, H, p}; }),
           py::arg("wheelbase") = AckermannGeometry{}.wheelbase,
           py::arg("encoder_offset") = AckermannGeometry{}.encoder_offset,
           py::arg("tracked_point") = Vec2::Zero().eval())
      .def_readwrite("wheelbase", &AckermannGeometry::wheelbase, "L [m]")
      .def_readwrite("encoder_offset", &AckermannGeometry::encoder_offset, "H [m], encoder left of the centre line")
      .def_readwrite("tracked_point", &AckermannGeometry::tracked_point, "(a, b) [m]: the point whose pose is the state")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"wheelbase", "encoder_offset", "tracked_point"}); });

  py::class_<AckermannModel, MotionModel, std::shared_ptr<AckermannModel>>(
      m, "AckermannModel", "Car-like (Ackermann) motion model; input AckermannControl.")
      .def(py::init<const AckermannGeometry&, double, double, NoiseForm>(), py::arg("geometry"),
           py::arg("sigma_speed"), py::arg("sigma_steering"), py::arg("form") = NoiseForm::Rate)
      .def(
          "body_velocity",
          [](const AckermannModel& a, const AckermannControl& u) {
            Eigen::Matrix2d J;
            const Eigen::Vector2d vw = a.bodyVelocity(u, &J);
            return py::make_tuple(vw, J);
          },
          py::arg("u"), "(vc, w) of input u and d(vc, w)/d(speed, steering).")
      .def_property_readonly("geometry", &AckermannModel::geometry, py::return_value_policy::copy)
      .def_property_readonly("sigma_speed", &AckermannModel::sigmaSpeed)
      .def_property_readonly("sigma_steering", &AckermannModel::sigmaSteering)
      .def_property_readonly("form", &AckermannModel::form);

  py::class_<OdometryModel, MotionModel, std::shared_ptr<OdometryModel>>(
      m, "OdometryModel", "Relative odometry model; input OdometryIncrement (its own covariance).")
      .def(py::init<>());

  // --- measurement models -------------------------------------------------------------------
  py::class_<MeasurementModel, std::shared_ptr<MeasurementModel>>(
      m, "MeasurementModel", "A sensor mounted at `mount` on the vehicle observing 2-D point landmarks (abstract).")
      .def("describe", &MeasurementModel::describe)
      .def(
          "predict",
          [](const MeasurementModel& s, const Pose2& x, const Vec2& y) {
            Mat23 J_x;
            Mat2 J_y;
            const Vec2 z = s.predict(x, y, &J_x, &J_y);
            return py::make_tuple(z, J_x, J_y);
          },
          py::arg("x"), py::arg("y"),
          "Predicted measurement of landmark y from pose x: (z, dz/dx (2x3), dz/dy (2x2)). "
          "Raises InvalidArgument where the model is degenerate.")
      .def(
          "inverse",
          [](const MeasurementModel& s, const Pose2& x, const Vec2& z) {
            Mat23 J_x;
            Mat2 J_z;
            const Vec2 y = s.inverse(x, z, &J_x, &J_z);
            return py::make_tuple(y, J_x, J_z);
          },
          py::arg("x"), py::arg("z"), "The landmark seen as z from pose x: (y, dy/dx (2x3), dy/dz (2x2)).")
      .def("residual", &MeasurementModel::residual, py::arg("z"), py::arg("zhat"),
           "z - zhat in measurement space (angles wrapped).")
      .def_property_readonly("period", &MeasurementModel::period,
                             "Per component, the period its residual wraps with (0: none): (0, 2 pi) for range-bearing.")
      .def_property_readonly("noise", py::overload_cast<>(&MeasurementModel::noise, py::const_), py::return_value_policy::copy,
                             "Default 2x2 measurement covariance.")
      .def_property_readonly("mount", &MeasurementModel::mount, py::return_value_policy::copy, "Sensor pose in the vehicle frame.")
      .def("__repr__", [](const MeasurementModel& s) { return "<" + s.describe() + ">"; });

  py::class_<RangeBearingModel, MeasurementModel, std::shared_ptr<RangeBearingModel>>(
      m, "RangeBearingModel", "Range-bearing sensor: z = (range [m], bearing [rad]).")
      .def(py::init<double, double, const Pose2&>(), py::arg("sigma_range"), py::arg("sigma_bearing"),
           py::arg("mount") = Pose2::Zero().eval())
      .def(py::init<const Mat2&, const Pose2&>(), py::arg("noise"), py::arg("mount") = Pose2::Zero().eval());

  py::class_<CartesianModel, MeasurementModel, std::shared_ptr<CartesianModel>>(
      m, "CartesianModel", "Point sensor: z = the landmark's (x, y) [m] in the sensor frame.")
      .def(py::init<const Mat2&, const Pose2&>(), py::arg("noise"), py::arg("mount") = Pose2::Zero().eval());

  m.def("diagonal_noise", &diagonalNoise, py::arg("sigma_1"), py::arg("sigma_2"),
        "diag(sigma_1^2, sigma_2^2).");

  // --- the dataset vocabulary (core/dataset.hpp) --------------------------------------------
  py::class_<TimedPose>(m, "TimedPose", "A pose (x, y, theta) at time t [s] (ground truth, trajectories).")
      .def(py::init([](double t, const Pose2& p) { return TimedPose{t, p}; }), py::arg("time") = 0.0,
           py::arg("pose") = Pose2::Zero().eval())
      .def_readwrite("time", &TimedPose::time)
      .def_readwrite("pose", &TimedPose::pose)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "pose"}); });

  py::class_<GpsFix>(m, "GpsFix", "A GPS fix: position [m] in the dataset's local frame at time t [s].")
      .def(py::init([](double t, const Vec2& p) { return GpsFix{t, p}; }), py::arg("time") = 0.0,
           py::arg("position") = Vec2::Zero().eval())
      .def_readwrite("time", &GpsFix::time)
      .def_readwrite("position", &GpsFix::position)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "position"}); });

  py::class_<ControlEvent>(m, "ControlEvent",
                           "A control or odometry record (input: VelocityControl, AckermannControl or "
                           "OdometryIncrement); pose: id of the pose reached, or -1.")
      .def(py::init([](double t, const MotionInput& u, long long pose) { return ControlEvent{t, u, pose}; }),
           py::arg("time"), py::arg("input"), py::arg("pose") = -1)
      .def_readwrite("time", &ControlEvent::time)
      .def_readwrite("input", &ControlEvent::input)
      .def_readwrite("pose", &ControlEvent::pose)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "input", "pose"}); });

  py::class_<ObservationEvent>(m, "ObservationEvent", "The observations made at one instant.")
      .def(py::init([](double t, const std::vector<Observation>& z) { return ObservationEvent{t, z}; }),
           py::arg("time"), py::arg("observations"))
      .def_readwrite("time", &ObservationEvent::time)
      .def_readwrite("observations", &ObservationEvent::observations, py::return_value_policy::copy)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "observations"}); });

  py::class_<OdometryRecord>(m, "OdometryRecord", "MRCLAM odometry row: time [s], v [m/s], w [rad/s].")
      .def(py::init<>())
      .def_readwrite("time", &OdometryRecord::time)
      .def_readwrite("v", &OdometryRecord::v)
      .def_readwrite("w", &OdometryRecord::w)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "v", "w"}); });

  m.attr("CLUTTER_SUBJECT") = kClutterSubject;
  py::class_<MeasurementRecord>(m, "MeasurementRecord",
                                "MRCLAM measurement row: time, subject (CLUTTER_SUBJECT: a false detection), range, bearing.")
      .def(py::init<>())
      .def_readwrite("time", &MeasurementRecord::time)
      .def_readwrite("subject", &MeasurementRecord::subject)
      .def_readwrite("range", &MeasurementRecord::range)
      .def_readwrite("bearing", &MeasurementRecord::bearing)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "subject", "range", "bearing"}); });

  py::class_<DropCounts>(m, "DropCounts", "Records dropped while reading, by reason.")
      .def(py::init<>())
      .def_readwrite("robot_measurements", &DropCounts::robot_measurements)
      .def_readwrite("unknown_barcodes", &DropCounts::unknown_barcodes)
      .def_readwrite("before_first_control", &DropCounts::before_first_control)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"robot_measurements", "unknown_barcodes", "before_first_control"});
      });

  py::class_<RobotLog>(m, "RobotLog",
                       "One robot's log in memory (the simulator's output; the MRCLAM layout). "
                       "List attributes are copied on access.")
      .def(py::init<>())
      .def_readwrite("source", &RobotLog::source)
      .def_readwrite("robot", &RobotLog::robot)
      .def_readwrite("odometry", &RobotLog::odometry, py::return_value_policy::copy)
      .def_readwrite("measurements", &RobotLog::measurements, py::return_value_policy::copy)
      .def_readwrite("groundtruth", &RobotLog::groundtruth, py::return_value_policy::copy)
      .def_readwrite("landmarks", &RobotLog::landmarks, py::return_value_policy::copy)
      .def_readwrite("noise", &RobotLog::noise, py::return_value_policy::copy)
      .def_readwrite("dropped", &RobotLog::dropped);

  py::class_<Step>(m, "Step", "One filter cycle: predict with u (ending at `time`), then update with the observations.")
      .def(py::init([](double t, const MotionInput& u, const std::vector<Observation>& z) { return Step{t, u, z}; }),
           py::arg("time"), py::arg("u"), py::arg("observations") = std::vector<Observation>{})
      .def_readwrite("time", &Step::time)
      .def_readwrite("u", &Step::u)
      .def_readwrite("observations", &Step::observations, py::return_value_policy::copy)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"time", "u", "observations"}); });

  py::class_<Dataset>(m, "Dataset",
                      "A dataset in memory: steps, ground truth, landmarks, noise. List attributes are "
                      "copied on access (read `steps` once, not in a loop).")
      .def(py::init<>())
      .def_readwrite("source", &Dataset::source)
      .def_readwrite("start_time", &Dataset::start_time)
      .def_readwrite("steps", &Dataset::steps, py::return_value_policy::copy)
      .def_readwrite("groundtruth", &Dataset::groundtruth, py::return_value_policy::copy)
      .def_readwrite("landmarks", &Dataset::landmarks, py::return_value_policy::copy)
      .def_readwrite("noise", &Dataset::noise, py::return_value_policy::copy)
      .def_readwrite("dropped", &Dataset::dropped)
      .def("__len__", [](const Dataset& d) { return d.steps.size(); });

  m.def("build_dataset", &buildDataset, py::arg("log"),
        "Merges a RobotLog's odometry and measurement stamps into filter steps (core/dataset.hpp).");
  m.def("interpolate_pose", &interpolatePose, py::arg("track"), py::arg("t"),
        "The pose of a time-sorted track at time t, interpolated linearly (clamped outside).");
}

}  // namespace seif::python
