// Result files are complete or absent: written under a temporary name and renamed.
#include <seif/core/errors.hpp>
#include "core/files.hpp"
#include "forwarding_filter.hpp"
#include <seif/io/results.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace seif;

fs::path freshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("seif-results-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for (auto it = fs::directory_iterator(dir); it != fs::directory_iterator(); ++it) ++n;
  return n;
}

/// An EKF whose covariance read-out fails at the third landmark, as an interrupted run would.
class FailingFilter : public test::ForwardingFilter {
 public:
  Mat2 landmarkCovariance(int id) const override {
    if (++calls_ == 3) throw std::runtime_error("interrupted");
    return ForwardingFilter::landmarkCovariance(id);
  }

 private:
  mutable int calls_ = 0;
};

TEST(AtomicFile, AFailedWriteLeavesNeitherTheFileNorATemporary) {
  const fs::path dir = freshDir("fail");
  FailingFilter filter;
  const Observation z[] = {{1, Vec2(1.0, 0.1), {}}, {2, Vec2(1.5, -0.2), {}}, {3, Vec2(2.0, 0.5), {}}, {4, Vec2(2.5, 1.0), {}}};
  filter.update(z);
  EXPECT_THROW(writeMapCsv(dir / "map.csv", filter), std::runtime_error);
  EXPECT_EQ(entries(dir), 0u);
  fs::remove_all(dir);
}

/// An EKF whose landmark 2 has a covariance of NaN (landmark 3: an estimate of NaN too).
class NonFiniteFilter : public test::ForwardingFilter {
 public:
  Mat2 landmarkCovariance(int id) const override {
    return id >= 2 ? Mat2::Constant(std::nan("")) : ForwardingFilter::landmarkCovariance(id);
  }
  Vec2 landmark(int id) const override { return id == 3 ? Vec2(std::nan(""), 0.0) : ForwardingFilter::landmark(id); }
};

TEST(MapCsv, ANaNIsNeverWritten) {
  // Refused, naming the landmark, with nothing written; or, for a failed run's map, its row
  // left out.
  const fs::path dir = freshDir("nan");
  NonFiniteFilter filter;
  const Observation z[] = {{1, Vec2(1.0, 0.1), {}}, {2, Vec2(1.5, -0.2), {}}, {3, Vec2(2.0, 0.5), {}}};
  filter.update(z);
  try {
    writeMapCsv(dir / "map.csv", filter);
    ADD_FAILURE() << "written";
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find("map.csv: landmark 2's covariance is not finite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(entries(dir), 0u);
  try {
    writeMapCsv(dir / "map.csv", filter, false);
    ADD_FAILURE() << "written";
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find("landmark 3's estimate is not finite"), std::string::npos) << e.what();
  }
  writeMapCsv(dir / "map.csv", filter, true, NonFiniteRows::Omit);
  std::ifstream in(dir / "map.csv");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  EXPECT_EQ(text.find("nan"), std::string::npos) << text;
  EXPECT_EQ(text.rfind("id,x,y,cov_xx,cov_xy,cov_yy\n1,", 0), 0u) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;  // the header and landmark 1
  fs::remove_all(dir);
}

TEST(AtomicFile, ACompleteWriteReplacesTheOldFile) {
  const fs::path dir = freshDir("ok");
  { std::ofstream(dir / "metrics.json") << "old"; }
  writeFileAtomically(dir / "metrics.json", "new\n");
  std::ifstream in(dir / "metrics.json");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "new\n");
  EXPECT_EQ(entries(dir), 1u);
  fs::remove_all(dir);
}

TEST(LandmarkTruthCsv, OneRowPerLandmarkByIdAtNineDigits) {
  const fs::path dir = freshDir("truth");
  writeLandmarkTruthCsv(dir / "landmarks_groundtruth.csv", {{7, Vec2(1.5, -2.25)}, {3, Vec2(0.123456789012, 4e-7)}});
  std::ifstream in(dir / "landmarks_groundtruth.csv");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "id,x,y\n3,0.123456789,4e-07\n7,1.5,-2.25\n");
  fs::remove_all(dir);
}

TEST(AtomicFile, UnwritableTargetsAreDataErrorsNamingThePath) {
  const fs::path dir = freshDir("bad");
  { std::ofstream(dir / "a_file") << "x"; }
  try {
    writeFileAtomically(dir / "a_file" / "map.csv", "x");
    FAIL() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("a_file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(requireWritableDirectory(dir / "a_file"), DataError);
  EXPECT_THROW(requireWritableDirectory(dir / "a_file" / "sub"), DataError);
  EXPECT_NO_THROW(requireWritableDirectory(dir / "new" / "sub"));
  EXPECT_TRUE(fs::is_directory(dir / "new" / "sub"));
  fs::remove_all(dir);
}

}  // namespace
