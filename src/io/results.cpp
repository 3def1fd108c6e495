#include <seif/core/errors.hpp>
#include <seif/io/results.hpp>

#include <cmath>
#include <cstdio>
#include <memory>

namespace seif {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File openForWriting(const std::filesystem::path& file) {
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  File f(std::fopen(file.c_str(), "w"));
  if (!f) throw DataError(file.string(), 0, "cannot open for writing");
  return f;
}

void finish(File f, const std::filesystem::path& file) {
  if (std::ferror(f.get()) || std::fclose(f.release()) != 0) {
    throw DataError(file.string(), 0, "write failed");
  }
}

}  // namespace

void writeTum(const std::filesystem::path& file, const std::vector<TimedPose>& trajectory) {
  File f = openForWriting(file);
  std::fprintf(f.get(), "# timestamp tx ty tz qx qy qz qw\n");
  for (const TimedPose& p : trajectory) {
    const double half = 0.5 * p.pose.z();
    std::fprintf(f.get(), "%.6f %.9g %.9g 0 0 0 %.9g %.9g\n", p.time, p.pose.x(), p.pose.y(),
                 std::sin(half), std::cos(half));
  }
  finish(std::move(f), file);
}

void writeMapCsv(const std::filesystem::path& file, const SlamFilter& filter) {
  File f = openForWriting(file);
  std::fprintf(f.get(), "id,x,y,cov_xx,cov_xy,cov_yy\n");
  for (int id : filter.landmarkIds()) {
    const Vec2 y = filter.landmark(id);
    const Mat2 P = filter.landmarkCovariance(id);
    std::fprintf(f.get(), "%d,%.9g,%.9g,%.9g,%.9g,%.9g\n", id, y.x(), y.y(), P(0, 0), P(0, 1),
                 P(1, 1));
  }
  finish(std::move(f), file);
}

}  // namespace seif
