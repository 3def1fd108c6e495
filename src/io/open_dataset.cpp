// openDataset(): the one entry to every reader (include/seif/io/event_source.hpp).
#include <seif/core/errors.hpp>
#include <seif/io/event_source.hpp>
#include <seif/io/graph_file.hpp>
#include "io/mrclam_source.hpp"
#include "io/victoria_park.hpp"

namespace seif {

std::unique_ptr<EventSource> openDataset(const std::filesystem::path& path, DatasetFormat format,
                                         const DatasetOptions& options) {
  if (format == DatasetFormat::Auto) {
    if (looksLikeMrclam(path)) {
      format = DatasetFormat::Mrclam;
    } else if (looksLikeVictoriaPark(path)) {
      format = DatasetFormat::VictoriaPark;
    } else if (looksLikeIsam(path)) {
      format = DatasetFormat::Isam;
    } else if (looksLikeG2o(path)) {
      format = DatasetFormat::G2o;
    } else {
      throw DataError(path.string(), 0,
                      "cannot tell the dataset's format; give it (format, --format) as one of: mrclam (a folder with "
                      "Barcodes.dat and RobotN_Odometry.dat), victoria-park (a folder with controls.txt and "
                      "tree_observations_associated_UTS.txt or tree_detections.txt), isam (a text file of ODOMETRY / LANDMARK / BR "
                      "records), g2o (a text file of VERTEX_SE2 / VERTEX_XY / EDGE_SE2 / EDGE_SE2_XY records)");
    }
  }
  // Options of one format only: refused with another, as a flag that would be ignored.
  const auto readAs = [&] { return path.string() + " is read as " + std::string(datasetFormatName(format)); };
  if (options.detections == Detections::Raw && format != DatasetFormat::VictoriaPark) {
    throw InvalidArgument("raw detections are read from a Victoria Park folder only (tree_detections.txt); " + readAs());
  }
  if (options.robot != 1 && format != DatasetFormat::Mrclam) {
    throw InvalidArgument("a robot number (" + std::to_string(options.robot) +
                          ") selects one robot's log of an MRCLAM folder only; " + readAs());
  }
  if (options.isam_landmarks_as_gtsam && format != DatasetFormat::Isam) {
    throw InvalidArgument("reading LANDMARK records as GTSAM does applies to an iSAM file only; " + readAs());
  }
  switch (format) {
    case DatasetFormat::Mrclam: return openMrclam(path, options);
    case DatasetFormat::VictoriaPark: return openVictoriaPark(path, options);
    case DatasetFormat::Isam: return openIsam(path, options);
    case DatasetFormat::G2o: return openG2o(path, options);
    case DatasetFormat::Auto: break;
  }
  throw InvalidArgument("openDataset: no reader for this format");
}

void convertDataset(const std::filesystem::path& in, DatasetFormat in_format, const std::filesystem::path& out,
                    GraphFormat to) {
  auto source = openDataset(in, in_format);
  writeGraph(out, *source, to);
}

}  // namespace seif
