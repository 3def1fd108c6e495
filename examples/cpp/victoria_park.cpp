// Victoria Park (Sydney): a car with an Ackermann model, a laser's tree detections with
// known association, GPS to compare with. `seif run` as one library call: it opens the
// dataset (any format: openDataset), streams it through the SEIF and writes the outputs.
//
//   victoria_park DATASET_DIR OUT_DIR      (DATASET_DIR: ../shared/data/victoria-park)
//
// Symbols used (from <seif/seif.hpp>, namespace seif):
//   RunRequest, runDataset, RunReport   the dataset, the filter spec -> trajectory.tum, map.csv, metrics.json
#include <seif/seif.hpp>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  using namespace seif;
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s DATASET_DIR OUT_DIR\n", argv[0]);
    return 1;
  }
  if (!std::filesystem::exists(argv[1])) {
    std::fprintf(stderr, "victoria_park: %s not found; skipped\n", argv[1]);
    return 77;  // the tests' "skipped"
  }
  RunRequest request;
  request.dataset = argv[1];
  request.filter = "seif";
  std::filesystem::create_directories(argv[2]);
  try {
    const RunReport r = runDataset(request, argv[2]);
    std::printf("%s: %zu steps, %zu landmarks, filter %.2f s\n", r.filter.c_str(), r.output.steps, r.landmarks,
                r.output.seconds);
    if (r.errors.gps) {
      std::printf("GPS error (aligned RMS over %zu fixes): %.2f m; dead reckoning %.2f m\n", r.errors.gps_fixes,
                  *r.errors.gps, r.errors.dead_reckoning_gps.value_or(-1.0));
    }
    std::printf("figure: seif plot %s\n", argv[2]);
    return r.errors.gps && *r.errors.gps < 5.0 ? 0 : 1;
  } catch (const Error& e) {  // every error seif throws, with what and where
    std::fprintf(stderr, "victoria_park: %s\n", e.what());
    return 2;
  }
}
