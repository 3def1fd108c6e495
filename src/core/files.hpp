#pragma once
// Files read and written whole, for every layer (checkpoints, readers, results).
// Output files are either complete or absent: written under a temporary name in the
// target's folder (".NAME.tmp-PID") and renamed into place only when every byte is written,
// so a run killed half-way never leaves a partial file posing as a result.
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace seif {

class AtomicFile {
 public:
  /// Creates the target's folder and opens the temporary file. Throws DataError naming the
  /// target when either fails.
  explicit AtomicFile(std::filesystem::path target);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  /// Removes the temporary file when commit() was not reached (an exception, a failure).
  ~AtomicFile();

  std::FILE* get() const { return file_; }
  const std::filesystem::path& target() const { return target_; }
  /// Flushes, closes and renames the temporary file to the target. Throws DataError.
  void commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
};

/// Writes `content` to `file` atomically (AtomicFile).
void writeFileAtomically(const std::filesystem::path& file, std::string_view content);

/// Throws DataError naming `dir` unless it exists (or can be created) and a file can be
/// created in it: called before a long computation, so a bad --out fails in a second.
void requireWritableDirectory(const std::filesystem::path& dir);

/// The text of `path`, or nullopt when it does not exist (a dangling link included).
/// Throws DataError naming the file when it exists but cannot be read.
std::optional<std::string> readFileIfExists(const std::filesystem::path& path);

/// Whether `path` exists as a regular file (following links); a link loop or an
/// unreadable entry is a DataError naming it.
bool regularFileExists(const std::filesystem::path& path);

}  // namespace seif
