#pragma once
// seif's public API in one include: #include <seif/seif.hpp>
//
//   core     poses, observations and the event vocabulary every source speaks; one error
//            base (seif::Error: DataError, NumericError, InvalidArgument, UnknownLandmark)
//   models   motion (velocity, Ackermann, odometry) and measurement (range-bearing,
//            Cartesian) models with their Jacobians
//   filters  SlamFilter (predict / update / marginal queries / removal and merge), built from
//            a spec ("ekf", "eif", "seif:sparsify=eseif", "batch") by makeFilter()
//   association  which landmark each observation is of when the data does not say: known,
//            nn, jcbb; provisional landmarks and merging (Associator)
//   io       openDataset() over every format (an EventSource), writers of results
//   sim      the paper's world and scalable worlds, as datasets
//   eval     the run loop with observers, runDataset (`seif run` as one call), the
//            experiments (paper, consistency, bench) and their metrics
#include <Eigen/Dense>  // the linear algebra the API speaks (poses, covariances)

#include <seif/association/association.hpp>
#include <seif/core/angles.hpp>
#include <seif/core/dataset.hpp>
#include <seif/core/errors.hpp>
#include <seif/core/types.hpp>
#include <seif/core/version.hpp>
#include <seif/eval/association_ceiling.hpp>
#include <seif/eval/bench.hpp>
#include <seif/eval/consistency.hpp>
#include <seif/eval/paper.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/eval/step_assembler.hpp>
#include <seif/eval/stats.hpp>
#include <seif/filters/checkpoint.hpp>
#include <seif/filters/factory.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/io/event_source.hpp>
#include <seif/io/graph_file.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/io/results.hpp>
#include <seif/models/ackermann_model.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_model.hpp>
#include <seif/sim/world.hpp>
