#include "binary_archive.hpp"

#include <seif/core/errors.hpp>
#include "core/files.hpp"

#include <cstring>
#include <limits>

namespace seif {

static_assert(std::numeric_limits<double>::is_iec559, "checkpoints store IEEE-754 doubles");

namespace {

enum Tag : std::uint8_t { kU64 = 1, kI64 = 2, kF64 = 3, kStr = 4, kF64s = 5, kSection = 6 };
constexpr std::uint32_t kByteOrderMark = 0x01020304u;
// Dimensions of a stored matrix: far beyond any map, small enough that rows * cols cannot
// overflow before it is checked against the bytes left.
constexpr std::uint64_t kMaxDimension = std::uint64_t{1} << 31;

const char* tagName(std::uint8_t t) {
  switch (t) {
    case kU64: return "u64";
    case kI64: return "i64";
    case kF64: return "f64";
    case kStr: return "string";
    case kF64s: return "f64 array";
    case kSection: return "section";
    default: return "unknown";
  }
}

std::uint64_t readLE(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

void appendLE(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

}  // namespace

std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

// ---------------------------------------------------------------- writer --------------

void ArchiveWriter::raw64(std::uint64_t v) { appendLE(payload_, v, 8); }

void ArchiveWriter::u64(std::uint64_t v) {
  tag(kU64);
  raw64(v);
}

void ArchiveWriter::i64(std::int64_t v) {
  tag(kI64);
  raw64(static_cast<std::uint64_t>(v));
}

void ArchiveWriter::f64(double v) {
  tag(kF64);
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  raw64(bits);
}

void ArchiveWriter::str(std::string_view s) {
  tag(kStr);
  raw64(s.size());
  payload_.append(s);
}

void ArchiveWriter::section(std::string_view name) {
  tag(kSection);
  raw64(name.size());
  payload_.append(name);
}

void ArchiveWriter::f64s(const double* v, std::size_t n) {
  tag(kF64s);
  raw64(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, &v[i], sizeof bits);
    raw64(bits);
  }
}

void ArchiveWriter::matrix(const Eigen::MatrixXd& m) {
  u64(static_cast<std::uint64_t>(m.rows()));
  u64(static_cast<std::uint64_t>(m.cols()));
  f64s(m.data(), static_cast<std::size_t>(m.size()));
}

void ArchiveWriter::vector(const Eigen::VectorXd& v) {
  u64(static_cast<std::uint64_t>(v.size()));
  f64s(v.data(), static_cast<std::size_t>(v.size()));
}

std::string ArchiveWriter::bytes() const {
  std::string out;
  out.reserve(kArchiveHeaderSize + payload_.size());
  out.append(kArchiveMagic);
  appendLE(out, kArchiveVersion, 4);
  appendLE(out, kByteOrderMark, 4);
  appendLE(out, payload_.size(), 8);
  appendLE(out, fnv1a64(payload_), 8);
  out.append(payload_);
  return out;
}

void ArchiveWriter::writeFile(const std::filesystem::path& path) const { writeFileAtomically(path, bytes()); }

// ---------------------------------------------------------------- reader --------------

ArchiveReader::ArchiveReader(std::string_view bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {
  if (bytes_.empty()) fail("empty file, not a seif checkpoint");
  if (bytes_.size() < kArchiveMagic.size() || bytes_.substr(0, kArchiveMagic.size()) != kArchiveMagic) {
    fail("not a seif checkpoint (no SEIFCKPT magic)");
  }
  pos_ = kArchiveMagic.size();
  if (bytes_.size() < kArchiveHeaderSize) {
    fail("truncated header: " + std::to_string(bytes_.size()) + " bytes, a checkpoint header has " +
         std::to_string(kArchiveHeaderSize));
  }
  version_ = static_cast<std::uint32_t>(readLE(bytes_.data() + 8, 4));
  if (version_ == 0 || version_ > kArchiveVersion) {
    fail("checkpoint format version " + std::to_string(version_) + " is not readable by this build (it reads 1.." +
         std::to_string(kArchiveVersion) + ")");
  }
  pos_ = 12;
  const auto bom = static_cast<std::uint32_t>(readLE(bytes_.data() + 12, 4));
  if (bom != kByteOrderMark) fail("bad byte-order mark (not a little-endian seif checkpoint)");
  pos_ = 16;
  const std::uint64_t size = readLE(bytes_.data() + 16, 8);
  const std::size_t have = bytes_.size() - kArchiveHeaderSize;
  if (size != have) {
    fail(std::string(size > have ? "truncated" : "trailing bytes") + ": the header promises " + std::to_string(size) +
         " payload bytes, the file has " + std::to_string(have));
  }
  pos_ = 24;
  if (readLE(bytes_.data() + 24, 8) != fnv1a64(bytes_.substr(kArchiveHeaderSize))) {
    fail("checksum mismatch: the checkpoint is corrupted");
  }
  pos_ = kArchiveHeaderSize;
}

void ArchiveReader::fail(const std::string& what) const {
  throw DataError(name_, 0, what + " at byte offset " + std::to_string(pos_));
}

void ArchiveReader::expectTag(std::uint8_t t, const char* what) {
  if (remaining() < 1) fail(std::string("truncated before ") + what);
  const auto found = static_cast<std::uint8_t>(bytes_[pos_]);
  if (found != t) {
    fail(std::string(what) + ": expected type " + tagName(t) + ", found type " + tagName(found) + " (tag " +
         std::to_string(found) + ")");
  }
  ++pos_;
}

std::uint64_t ArchiveReader::raw64(const char* what) {
  if (remaining() < 8) fail(std::string("truncated in ") + what);
  const std::uint64_t v = readLE(bytes_.data() + pos_, 8);
  pos_ += 8;
  return v;
}

std::uint64_t ArchiveReader::u64(const char* what) {
  expectTag(kU64, what);
  return raw64(what);
}

std::int64_t ArchiveReader::i64(const char* what) {
  expectTag(kI64, what);
  return static_cast<std::int64_t>(raw64(what));
}

std::int64_t ArchiveReader::i64In(const char* what, std::int64_t lo, std::int64_t hi) {
  const std::size_t at = pos_;
  const std::int64_t v = i64(what);
  if (v < lo || v > hi) {
    pos_ = at;
    fail(std::string(what) + " " + std::to_string(v) + " is out of range " + std::to_string(lo) + ".." +
         std::to_string(hi));
  }
  return v;
}

std::uint64_t ArchiveReader::u64Max(const char* what, std::uint64_t hi) {
  const std::size_t at = pos_;
  const std::uint64_t v = u64(what);
  if (v > hi) {
    pos_ = at;
    fail(std::string(what) + " " + std::to_string(v) + " is out of range 0.." + std::to_string(hi));
  }
  return v;
}

double ArchiveReader::f64(const char* what) {
  expectTag(kF64, what);
  const std::uint64_t bits = raw64(what);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string ArchiveReader::str(const char* what) {
  expectTag(kStr, what);
  const std::uint64_t n = raw64(what);
  if (n > remaining()) fail(std::string(what) + ": length " + std::to_string(n) + " exceeds the bytes left");
  std::string s(bytes_.substr(pos_, static_cast<std::size_t>(n)));
  pos_ += static_cast<std::size_t>(n);
  return s;
}

void ArchiveReader::section(std::string_view name) {
  const std::size_t at = pos_;
  expectTag(kSection, "section marker");
  const std::uint64_t n = raw64("section marker");
  if (n != name.size() || n > remaining() || bytes_.substr(pos_, name.size()) != name) {
    pos_ = at;
    fail("expected section '" + std::string(name) + "'");
  }
  pos_ += name.size();
}

std::size_t ArchiveReader::count(const char* what, std::size_t min_bytes) {
  const std::size_t at = pos_;
  const std::uint64_t n = u64(what);
  if (n > remaining() / (min_bytes == 0 ? 1 : min_bytes)) {
    pos_ = at;
    fail(std::string(what) + " " + std::to_string(n) + " exceeds what the bytes left can hold");
  }
  return static_cast<std::size_t>(n);
}

void ArchiveReader::f64s(const char* what, double* v, std::size_t n) {
  const std::size_t at = pos_;
  expectTag(kF64s, what);
  const std::uint64_t stored = raw64(what);
  if (stored != n) {
    pos_ = at;
    fail(std::string(what) + ": expected " + std::to_string(n) + " values, found " + std::to_string(stored));
  }
  if (n > remaining() / 8) fail(std::string("truncated in ") + what);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t bits = readLE(bytes_.data() + pos_, 8);
    std::memcpy(&v[i], &bits, sizeof bits);
    pos_ += 8;
  }
}

void ArchiveReader::notFinite(const char* what) const {
  fail(std::string(what) + " holds a NaN or an infinity");
}

Eigen::MatrixXd ArchiveReader::matrix(const char* what, bool finite) {
  const std::uint64_t rows = u64Max(what, kMaxDimension);
  const std::uint64_t cols = u64Max(what, kMaxDimension);
  if (rows * cols > remaining() / 8) fail(std::string(what) + ": " + std::to_string(rows) + "x" + std::to_string(cols) +
                                          " exceeds the bytes left");
  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  f64s(what, m.data(), static_cast<std::size_t>(m.size()));
  if (finite && !m.allFinite()) notFinite(what);
  return m;
}

Eigen::VectorXd ArchiveReader::vector(const char* what, bool finite) {
  const std::uint64_t n = u64Max(what, kMaxDimension);
  if (n > remaining() / 8) fail(std::string(what) + ": " + std::to_string(n) + " values exceed the bytes left");
  Eigen::VectorXd v(static_cast<Eigen::Index>(n));
  f64s(what, v.data(), static_cast<std::size_t>(n));
  if (finite && !v.allFinite()) notFinite(what);
  return v;
}

void ArchiveReader::finish() {
  if (remaining() != 0) fail(std::to_string(remaining()) + " unread bytes after the last section");
}

}  // namespace seif
