// Golden outputs: the numbers seif produced before the library refactor (issue "seif as a
// library people embed"), recorded as digests in tests/golden/digests.txt. Each case runs
// the `seif` command as a user would and digests its output files, keeping every number a
// run computes and dropping only what measures the machine or names the invocation
// (timings, thread counts, the command line, the dataset path and version). JSON numbers are printed to round-trip (17 significant
// digits), so a change in the last bit of an error metric fails the test.
//
// Bit-identity holds only for the build the digests were recorded with (Release, the same
// compiler): the test is registered for Release builds without sanitizers. To re-record
// after a change that is meant to change numbers, run with SEIF_GOLDEN_RECORD=1 and say why
// in the commit.
#include "../cli_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using seif::test::runCli;
using seif::test::scratchDir;
using seif::test::slurp;

namespace {

const std::string kData = SEIF_SHARED_DATA_DIR;
const fs::path kDigests = fs::path(SEIF_SOURCE_DIR) / "tests" / "golden" / "digests.txt";

/// Keys whose values describe the machine or the invocation, not the estimate (the dataset
/// key holds the input path as typed, which differs between checkouts).
bool machineKey(const std::string& key) {
  for (const char* s : {"seconds", "us_per", "jobs", "command_line", "version", "time_definition", "time_unit"}) {
    if (key.find(s) != std::string::npos) return true;
  }
  return key == "dataset";
}

void dropMachineKeys(nlohmann::json& j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) {
      if (machineKey(it.key())) {
        it = j.erase(it);
      } else {
        dropMachineKeys(*it);
        ++it;
      }
    }
  } else if (j.is_array()) {
    for (auto& v : j) dropMachineKeys(v);
  }
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

/// Digest of every output file of a run folder (figures and tables for people excluded:
/// the tables repeat results.json's numbers beside timings, the figures are pixels).
std::map<std::string, std::string> digestFolder(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const fs::path p = entry.path();
    const std::string ext = p.extension().string();
    std::string canonical;
    if (ext == ".json") {
      nlohmann::json j = nlohmann::json::parse(slurp(p));
      dropMachineKeys(j);
      canonical = j.dump();
    } else if (ext == ".csv" || ext == ".tum") {
      canonical = slurp(p);
    } else {
      continue;
    }
    std::ostringstream hex;
    hex << std::hex << fnv1a(canonical);
    out[fs::relative(p, dir).string()] = hex.str();
  }
  return out;
}

std::map<std::string, std::string> readDigests() {
  std::map<std::string, std::string> d;
  std::ifstream in(kDigests);
  std::string key, value;
  while (in >> key >> value) d[key] = value;
  return d;
}

struct GoldenCase {
  std::string name;
  std::string args;  // after `seif`, without --out
  std::string needs;  // a data path that must exist, or empty
};

std::vector<GoldenCase> cases() {
  std::vector<GoldenCase> c = {
      {"paper30", "paper --runs 30 --jobs 2", ""},
      {"consistency10", "consistency --runs 10 --jobs 2", ""},
  };
  const std::string mrclam = kData + "/mrclam/MRCLAM_Dataset6";
  for (const char* filter : {"ekf", "seif"}) {
    for (int robot = 1; robot <= 5; ++robot) {
      c.push_back({"mrclam6_robot" + std::to_string(robot) + "_" + filter,
                   "run --dataset " + mrclam + " --robot " + std::to_string(robot) + " --filter " + filter, mrclam});
    }
    c.push_back({std::string("victoria_park_") + filter,
                 "run --dataset " + kData + "/victoria-park --filter " + filter, kData + "/victoria-park"});
  }
  return c;
}

TEST(Golden, OutputsEqualThoseBeforeTheRefactor) {
  const bool record = std::getenv("SEIF_GOLDEN_RECORD") != nullptr;
  const std::map<std::string, std::string> expected = readDigests();
  std::map<std::string, std::string> recorded;
  for (const GoldenCase& gc : cases()) {
    if (!gc.needs.empty() && !fs::exists(gc.needs)) {
      std::cout << "[golden] " << gc.name << " skipped: " << gc.needs << " not found\n";
      continue;
    }
    const auto dir = scratchDir("golden-" + gc.name);
    const auto r = runCli(gc.args + " --out " + dir.string(), 600);
    ASSERT_EQ(r.status, 0) << gc.name << ": " << r.err;
    const auto digests = digestFolder(dir);
    ASSERT_FALSE(digests.empty()) << gc.name << " wrote no output";
    for (const auto& [file, digest] : digests) {
      const std::string key = gc.name + "/" + file;
      recorded[key] = digest;
      if (record) continue;
      const auto it = expected.find(key);
      if (it == expected.end()) {  // a file added since: nothing to compare it with
        std::cout << "[golden] " << key << " is new (no recorded digest)\n";
        continue;
      }
      EXPECT_EQ(digest, it->second) << key << " differs from the golden output (`seif " << gc.args << "`)";
    }
    for (const auto& [key, digest] : expected) {
      if (key.rfind(gc.name + "/", 0) == 0 && !record) {
        EXPECT_TRUE(recorded.count(key)) << key << " is no longer written";
      }
    }
    fs::remove_all(dir);
  }
  if (record) {
    std::ofstream out(kDigests);
    for (const auto& [key, digest] : recorded) out << key << " " << digest << "\n";
    std::cout << "[golden] recorded " << recorded.size() << " digests in " << kDigests << "\n";
  }
}

}  // namespace
