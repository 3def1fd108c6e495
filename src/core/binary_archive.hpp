#pragma once
// The versioned binary container of checkpoints (docs/checkpoints.md): internal to the
// library. A file is a 32-byte header and a payload:
//   offset  0  "SEIFCKPT"                       magic, 8 bytes
//   offset  8  u32 format version               kArchiveVersion
//   offset 12  u32 0x01020304                   byte-order mark (the file is little-endian)
//   offset 16  u64 payload size                 the bytes after the header
//   offset 24  u64 FNV-1a 64 of the payload     checksum
//   offset 32  payload: a sequence of tagged values, each a 1-byte type tag and its bytes
// Every integer is little-endian whatever the host; a double is its IEEE-754 bits as a u64
// (bit-exact round trip, NaN payloads included). Lengths are checked against the bytes
// left before anything is allocated. Every reader error is a DataError naming the file and
// the byte offset.
#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace seif {

inline constexpr std::string_view kArchiveMagic = "SEIFCKPT";
inline constexpr std::uint32_t kArchiveVersion = 14;  // 2: the config no longer holds noise sigmas; 3: seif blanket;
                                                      // 4: seif covariance bounds; 5: seif deferred motion;
                                                      // 6: seif conservative sparsification's scale;
                                                      // 7: seif gauge rule; 8: seif mean's coarse level;
                                                      // 9: its kept rows without their robot terms;
                                                      // 10: whether the seif's robot-active block is solved;
                                                      // 11: seif stale-first deactivation;
                                                      // 12: seif mean's over-relaxation;
                                                      // 13: seif wildfire relaxation order;
                                                      // 14: seif controls since the last observation
inline constexpr std::size_t kArchiveHeaderSize = 32;

inline constexpr std::uint64_t kFnv1a64Basis = 0xcbf29ce484222325ULL;

/// FNV-1a 64 of `bytes` (the payload checksum), continuing from `hash` (the value so far
/// of the bytes before them; the offset basis for none).
std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash = kFnv1a64Basis);

class ArchiveWriter {
 public:
  void u64(std::uint64_t v);
  void i64(std::int64_t v);
  void f64(double v);
  void str(std::string_view s);
  /// A named section marker; the reader checks the name.
  void section(std::string_view name);
  /// A count of elements that follow.
  void count(std::size_t n) { u64(n); }
  /// `n` doubles, bit-exact.
  void f64s(const double* v, std::size_t n);
  /// A fixed-size matrix (its coefficients in storage order; aligned or not).
  template <int R, int C, int Options>
  void fixed(const Eigen::Matrix<double, R, C, Options>& m) {
    f64s(m.data(), static_cast<std::size_t>(R * C));
  }
  /// A dynamic matrix or vector: rows, cols, coefficients.
  void matrix(const Eigen::MatrixXd& m);
  void vector(const Eigen::VectorXd& v);

  /// The whole file: header and payload.
  std::string bytes() const;
  /// bytes(), written atomically (AtomicFile).
  void writeFile(const std::filesystem::path& path) const;

 private:
  void tag(std::uint8_t t) { payload_.push_back(static_cast<char>(t)); }
  void raw64(std::uint64_t v);
  std::string payload_;
};

class ArchiveReader {
 public:
  /// Checks the header (magic, version, byte order, size, checksum). `bytes` must outlive
  /// the reader. Throws DataError naming `name`.
  ArchiveReader(std::string_view bytes, std::string name);

  std::uint32_t version() const { return version_; }
  std::uint64_t u64(const char* what);
  std::int64_t i64(const char* what);
  /// An i64 in [lo, hi].
  std::int64_t i64In(const char* what, std::int64_t lo, std::int64_t hi);
  /// A u64 in [0, hi].
  std::uint64_t u64Max(const char* what, std::uint64_t hi);
  double f64(const char* what);
  std::string str(const char* what);
  void section(std::string_view name);
  /// A count of elements of at least `min_bytes` each: at most what the bytes left can hold.
  std::size_t count(const char* what, std::size_t min_bytes);
  void f64s(const char* what, double* v, std::size_t n);
  /// With `finite`, a NaN or infinity is an error (a filter's state never holds one).
  template <int R, int C, int Options>
  void fixed(const char* what, Eigen::Matrix<double, R, C, Options>& m, bool finite = false) {
    f64s(what, m.data(), static_cast<std::size_t>(R * C));
    if (finite && !m.allFinite()) notFinite(what);
  }
  Eigen::MatrixXd matrix(const char* what, bool finite = false);
  Eigen::VectorXd vector(const char* what, bool finite = false);
  /// Throws unless every byte was read.
  void finish();

  /// Throws DataError(name, 0, what + " at byte offset N").
  [[noreturn]] void fail(const std::string& what) const;
  [[noreturn]] void notFinite(const char* what) const;
  const std::string& name() const { return name_; }
  std::size_t offset() const { return pos_; }

 private:
  void expectTag(std::uint8_t t, const char* what);
  std::uint64_t raw64(const char* what);
  std::size_t remaining() const { return bytes_.size() - pos_; }

  std::string_view bytes_;
  std::string name_;
  std::size_t pos_ = 0;
  std::uint32_t version_ = 0;
};

}  // namespace seif
