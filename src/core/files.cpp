// Files read and written whole (src/core/files.hpp).
#include <seif/core/errors.hpp>
#include "core/files.hpp"

#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <optional>
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

bool regularFileExists(const fs::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) return false;
  if (ec == std::errc::too_many_symbolic_link_levels) {
    throw DataError(name, 0, "symbolic-link loop: " + ec.message());
  }
  if (ec) throw DataError(name, 0, "cannot access file: " + ec.message());
  if (!fs::is_regular_file(status)) throw DataError(name, 0, "not a regular file");
  return true;
}

std::optional<std::string> readFileIfExists(const fs::path& path) {
  if (!regularFileExists(path)) return std::nullopt;
  const std::string name = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataError(name, 0, "cannot open file for reading");
  std::string text;
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (!ec) text.reserve(static_cast<std::size_t>(size));
  std::array<char, 1 << 16> chunk{};
  while (in.read(chunk.data(), chunk.size()) || in.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw DataError(name, 0, "read error");
  return text;
}

}  // namespace seif
