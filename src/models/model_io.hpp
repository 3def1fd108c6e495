#pragma once
// Motion and sensor models in a checkpoint (docs/checkpoints.md): kind and parameters.
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>

#include <memory>

namespace seif {

class ArchiveWriter;
class ArchiveReader;

/// Throws InvalidArgument for a model that is not one of the library's own.
void writeMotionModel(ArchiveWriter& out, const MotionModel& model);
void writeSensorModel(ArchiveWriter& out, const MeasurementModel& model);
/// Throw DataError for an unknown kind or parameters the model refuses.
std::shared_ptr<const MotionModel> readMotionModel(ArchiveReader& in);
std::shared_ptr<const MeasurementModel> readSensorModel(ArchiveReader& in);

}  // namespace seif
