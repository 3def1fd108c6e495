#include <seif/core/errors.hpp>
#include "io/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace seif {
namespace fs = std::filesystem;

namespace {

std::string systemMessage(int err) { return std::generic_category().message(err); }

void createFolder(const fs::path& dir, const std::string& name_for_errors) {
  if (dir.empty()) return;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw DataError(name_for_errors, 0, "cannot create folder " + dir.string() + ": " + ec.message());
}

}  // namespace

AtomicFile::AtomicFile(fs::path target) : target_(std::move(target)) {
  createFolder(target_.parent_path(), target_.string());
  std::string name = ".";  // built by append: GCC 12 warns (-Wrestrict) on the + chain
  name.append(target_.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  temp_ = target_.parent_path() / name;
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) {
    throw DataError(target_.string(), 0, "cannot open for writing: " + systemMessage(errno));
  }
}

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::commit() {
  std::FILE* f = file_;
  file_ = nullptr;
  const bool failed = std::ferror(f) != 0;
  const bool closed = std::fclose(f) == 0;
  std::error_code ec;
  if (failed || !closed) {
    fs::remove(temp_, ec);
    throw DataError(target_.string(), 0, "write failed");
  }
  fs::rename(temp_, target_, ec);
  if (ec) {
    std::error_code ignore;
    fs::remove(temp_, ignore);
    throw DataError(target_.string(), 0, "cannot rename the finished file into place: " + ec.message());
  }
}

void writeFileAtomically(const fs::path& file, std::string_view content) {
  AtomicFile out(file);
  if (!content.empty()) std::fwrite(content.data(), 1, content.size(), out.get());
  out.commit();
}

void requireWritableDirectory(const fs::path& dir) {
  const std::string name = dir.string();
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw DataError(name, 0, "output path exists and is not a folder");
  }
  createFolder(dir, name);
  const fs::path probe = dir / (".seif-write-test-" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw DataError(name, 0, "output folder is not writable: " + systemMessage(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

}  // namespace seif
