#include <seif/core/errors.hpp>
#include "model_io.hpp"

#include "core/binary_archive.hpp"

#include <seif/models/ackermann_model.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_model.hpp>

#include <stdexcept>
#include <string>

namespace seif {

namespace {

NoiseForm readForm(ArchiveReader& in) {
  return in.u64Max("noise form", 1) == 0 ? NoiseForm::PerStep : NoiseForm::Rate;
}
std::uint64_t formCode(NoiseForm f) { return f == NoiseForm::PerStep ? 0 : 1; }

/// A model constructor's refusal (ModelError) as a DataError at the model's offset.
template <class Make>
auto construct(ArchiveReader& in, const char* what, Make make) {
  try {
    return make();
  } catch (const InvalidArgument& e) {
    in.fail(std::string("invalid ") + what + ": " + e.what());
  }
}

}  // namespace

void writeMotionModel(ArchiveWriter& out, const MotionModel& model) {
  out.section("motion");
  if (const auto* v = dynamic_cast<const VelocityModel*>(&model)) {
    out.str("velocity");
    out.f64(v->sigmaV());
    out.f64(v->sigmaW());
    out.u64(formCode(v->form()));
  } else if (const auto* a = dynamic_cast<const AckermannModel*>(&model)) {
    out.str("ackermann");
    out.f64(a->geometry().wheelbase);
    out.f64(a->geometry().encoder_offset);
    out.fixed(a->geometry().tracked_point);
    out.f64(a->sigmaSpeed());
    out.f64(a->sigmaSteering());
    out.u64(formCode(a->form()));
  } else if (dynamic_cast<const OdometryModel*>(&model)) {
    out.str("odometry");
  } else {
    throw InvalidArgument("checkpoint: cannot save the motion model '" + model.describe() +
                                "' (not one of the library's models)");
  }
}

std::shared_ptr<const MotionModel> readMotionModel(ArchiveReader& in) {
  in.section("motion");
  const std::string kind = in.str("motion model kind");
  if (kind == "velocity") {
    const double sigma_v = in.f64("sigma_v");
    const double sigma_w = in.f64("sigma_w");
    const NoiseForm form = readForm(in);
    return construct(in, "velocity model", [&] { return std::make_shared<const VelocityModel>(sigma_v, sigma_w, form); });
  }
  if (kind == "ackermann") {
    AckermannGeometry g;
    g.wheelbase = in.f64("wheelbase");
    g.encoder_offset = in.f64("encoder offset");
    in.fixed("tracked point", g.tracked_point);
    const double sigma_speed = in.f64("sigma_speed");
    const double sigma_steering = in.f64("sigma_steering");
    const NoiseForm form = readForm(in);
    return construct(in, "Ackermann model",
                     [&] { return std::make_shared<const AckermannModel>(g, sigma_speed, sigma_steering, form); });
  }
  if (kind == "odometry") return std::make_shared<const OdometryModel>();
  in.fail("unknown motion model '" + kind + "'");
}

void writeSensorModel(ArchiveWriter& out, const MeasurementModel& model) {
  out.section("sensor");
  if (dynamic_cast<const RangeBearingModel*>(&model)) {
    out.str("range-bearing");
  } else if (dynamic_cast<const CartesianModel*>(&model)) {
    out.str("cartesian");
  } else {
    throw InvalidArgument("checkpoint: cannot save the sensor model '" + model.describe() +
                                "' (not one of the library's models)");
  }
  out.fixed(model.noise());
  out.fixed(model.mount());
}

std::shared_ptr<const MeasurementModel> readSensorModel(ArchiveReader& in) {
  in.section("sensor");
  const std::string kind = in.str("sensor model kind");
  if (kind != "range-bearing" && kind != "cartesian") in.fail("unknown sensor model '" + kind + "'");
  Mat2 noise;
  Pose2 mount;
  in.fixed("sensor noise", noise);
  in.fixed("sensor mount", mount);
  return construct(in, "sensor model", [&]() -> std::shared_ptr<const MeasurementModel> {
    if (kind == "cartesian") return std::make_shared<const CartesianModel>(noise, mount);
    return std::make_shared<const RangeBearingModel>(noise, mount);
  });
}

}  // namespace seif
