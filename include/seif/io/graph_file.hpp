#pragma once
// Readers and writers of the two pose-graph text formats the field exchanges, as event
// streams (pose ids in time order: a filter needs the chain in the order it was driven).
//
// iSAM / GTSAM text (victoria-park-isam/victoria_park.txt is one; GTSAM's dataset.cpp):
//   ODOMETRY id1 id2 dx dy dth  c11 c12 c13 c22 c23 c33   pose id2 in the frame of pose id1,
//                                                          then the upper triangle of its COVARIANCE
//   LANDMARK pose lm x y  c11 c12 c22                     the landmark in the pose's frame, covariance
//   BR pose lm bearing range sigma_bearing sigma_range    bearing-range (standard deviations)
// g2o 2-D (types_slam2d):
//   VERTEX_SE2 id x y th  |  VERTEX_XY id x y             initial estimates
//   EDGE_SE2 id1 id2 dx dy dth  i11 i12 i13 i22 i23 i33   relative pose, INFORMATION upper triangle
//   EDGE_SE2_XY pose lm x y  i11 i12 i22                  landmark in the pose's frame, information
//
// Rules (every violation is a DataError "file:line: what"): pose and landmark ids share one
// integer space, and an id is either a pose or a landmark; the first odometry record starts
// the chain at its id1 and every later one starts at the pose the previous one reached
// (records in time order) and reaches a new pose; an observation is made from the current
// pose (or, before any odometry, from the chain's first pose); covariances and information
// matrices must be symmetric positive definite; a landmark id must fit an int. Unknown tags
// are refused, naming the supported ones. A file holds one kind of landmark observation:
// LANDMARK (Cartesian) or BR (range-bearing), not both.
//
// Events: the pose reached by the k-th odometry record has time k (the files have no
// stamps; the start pose has time 0): ControlEvent{k, OdometryIncrement{(dx, dy, dth), C}}
// then ObservationEvent{k, ...} with each observation's own covariance. Models: OdometryModel
// and CartesianModel (LANDMARK, EDGE_SE2_XY) or RangeBearingModel (BR) at the vehicle's origin.
// Start pose: g2o, the VERTEX_SE2 of the chain's first pose when it precedes the first edge;
// otherwise the origin. Noise comes from the records; DatasetOptions::noise must be empty.
#include <seif/io/event_source.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace seif {

bool looksLikeIsam(const std::filesystem::path& path);  ///< a file whose first record is ODOMETRY, LANDMARK or BR
bool looksLikeG2o(const std::filesystem::path& path);   ///< a file whose first record is VERTEX_* or EDGE_*

std::unique_ptr<EventSource> openIsam(const std::filesystem::path& file, const DatasetOptions& options = {});
std::unique_ptr<EventSource> openG2o(const std::filesystem::path& file, const DatasetOptions& options = {});
/// The same on text in memory (`text` must outlive the source), named `name` in messages.
std::unique_ptr<EventSource> openIsamText(const std::string& name, std::string_view text, const DatasetOptions& options = {});
std::unique_ptr<EventSource> openG2oText(const std::string& name, std::string_view text, const DatasetOptions& options = {});

/// Writes `source` as an iSAM or g2o file (atomically), with the source's pose ids
/// (ControlEvent::pose, DatasetInfo::start_pose_id) and landmark ids, records in the
/// source's order. g2o also gets VERTEX_SE2 (dead reckoning from the start pose)
/// and VERTEX_XY (each landmark from its first observation) initial estimates. Numbers are
/// written in the shortest form that reads back bit-identical; g2o's information matrices
/// are the inverses of the covariances (exact for the diagonal ones of victoria_park.txt).
/// Throws DataError for a source that is not an odometry stream with pose ids (a graph file),
/// and for range-bearing observations in g2o (EDGE_SE2_XY is Cartesian).
enum class GraphFormat { Isam, G2o };
/// "isam" | "g2o"; throws InvalidArgument for another name.
GraphFormat parseGraphFormat(std::string_view name);
std::string_view graphFormatName(GraphFormat format);
void writeGraph(const std::filesystem::path& file, EventSource& source, GraphFormat format);

/// openDataset(in, in_format) then writeGraph(out, to): `seif convert`.
void convertDataset(const std::filesystem::path& in, DatasetFormat in_format, const std::filesystem::path& out,
                    GraphFormat to);

}  // namespace seif
