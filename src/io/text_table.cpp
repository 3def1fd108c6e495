// The strict text-table parser shared by every reader (src/io/text_table.hpp).
#include "io/text_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>

namespace seif {
namespace fs = std::filesystem;

std::string formatDouble(double x) {
  std::array<char, 64> buf{};
  const auto res = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return std::string(buf.data(), res.ptr);
}

std::string quotedField(std::string_view field) {
  constexpr std::size_t kMax = 40;
  std::string q(1, '\'');
  q.append(field.substr(0, std::min(field.size(), kMax)));
  if (field.size() > kMax) q.append("...");
  q.push_back('\'');
  return q;
}

TextTable::TextTable(std::string name, std::string_view text) : name_(std::move(name)), text_(text) {}

TextTable TextTable::open(const fs::path& path) {
  if (!regularFileExists(path)) throw DataError(path.string(), 0, "missing required file");
  TextTable t(path.string(), {});
  t.file_ = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*t.file_) throw DataError(path.string(), 0, "cannot open file for reading");
  return t;
}

TextTable::TextTable(TextTable&&) noexcept = default;
TextTable& TextTable::operator=(TextTable&&) noexcept = default;
TextTable::~TextTable() = default;

std::size_t TextTable::offset() const {
  return file_ ? consumed_ : std::min(pos_, text_.size());
}

namespace {
/// UTF-8's byte order mark, which some editors put at a text file's start: not data.
constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";
}  // namespace

bool TextTable::next() {
  named_ = 0;
  if (file_) {
    while (std::getline(*file_, buffer_)) {
      ++line_;
      consumed_ += buffer_.size() + 1;
      if (line_ == 1 && buffer_.starts_with(kByteOrderMark)) buffer_.erase(0, kByteOrderMark.size());
      if (split(buffer_)) return true;
    }
    if (file_->bad()) throw DataError(name_, line_, "read error");
    return false;
  }
  while (pos_ < text_.size()) {
    std::size_t eol = text_.find('\n', pos_);
    if (eol == std::string_view::npos) eol = text_.size();
    std::string_view line(text_.data() + pos_, eol - pos_);
    pos_ = eol + 1;
    ++line_;
    if (line_ == 1 && line.starts_with(kByteOrderMark)) line.remove_prefix(kByteOrderMark.size());
    if (split(line)) return true;
  }
  return false;
}

namespace {
bool isBlank(char c) {
  switch (c) {
    case ' ': case '\t': case '\r': case '\v': case '\f': return true;
    default: return false;
  }
}
}  // namespace

bool TextTable::split(std::string_view line) {
  std::size_t i = 0;
  std::size_t n = 0;
  while (true) {
    while (i < line.size() && isBlank(line[i])) ++i;
    if (i == line.size()) break;
    if (n == 0 && line[i] == '#') return false;
    const std::size_t start = i;
    while (i < line.size() && !isBlank(line[i])) ++i;
    if (n < kMaxFields) fields_[n] = line.substr(start, i - start);
    ++n;
  }
  if (n > kMaxFields) {
    count_ = 0;
    fail("too many fields (" + std::to_string(n) + ", at most " + std::to_string(kMaxFields) + ")");
  }
  count_ = n;
  return n > 0;
}

void TextTable::expect(std::initializer_list<const char*> columns, std::string_view what) {
  named_ = std::min(columns.size(), kMaxFields);
  std::copy(columns.begin(), columns.begin() + static_cast<std::ptrdiff_t>(named_), columns_.begin());
  if (count_ == columns.size()) return;
  std::string names;
  for (const char* c : columns) {
    if (!names.empty()) names += ' ';
    names += c;
  }
  std::string msg = "expected " + std::to_string(columns.size()) + " fields (" + names + ")";
  if (!what.empty()) msg.append(" in ").append(what);
  fail(msg + ", found " + std::to_string(count_));
}

std::string TextTable::columnName(std::size_t col) const {
  std::string s("column ");
  s.append(std::to_string(col + 1));
  if (col < named_) s.append(" (").append(columns_[col]).append(")");
  return s;
}

double TextTable::real(std::size_t col) const {
  const std::string_view f = fields_[col];
  // An explicit sign, as printf's "%+f" writes it ("+0.02"); from_chars takes only '-'.
  const std::string_view number = f.size() > 1 && f[0] == '+' && f[1] != '-' && f[1] != '+' ? f.substr(1) : f;
  double value = 0.0;
  const auto res = std::from_chars(number.data(), number.data() + number.size(), value);
  if (res.ec == std::errc::result_out_of_range && res.ptr == number.data() + number.size()) {
    fail("number " + quotedField(f) + " out of range in " + columnName(col));
  }
  if (res.ec != std::errc() || res.ptr != number.data() + number.size()) {
    fail("bad number " + quotedField(f) + " in " + columnName(col));
  }
  if (!std::isfinite(value)) fail("non-finite number " + quotedField(f) + " in " + columnName(col));
  return value;
}

double TextTable::range(std::size_t col) const {
  const double value = real(col);
  if (!(value > 0.0)) fail("range " + formatDouble(value) + " must be positive");
  if (value > kMaxRange) fail("range " + formatDouble(value) + " m is beyond 10^6 m");
  return value;
}

double TextTable::coordinate(std::size_t col) const {
  const double value = real(col);
  if (std::abs(value) > kMaxRange) fail(formatDouble(value) + " m in " + columnName(col) + " is beyond 10^6 m");
  return value;
}

double TextTable::angle(std::size_t col) const {
  const double value = real(col);
  constexpr double kTurn = 6.283185307179586;
  // The printed precision's slack, but never more than half a radian ("1e1" is not 2 pi).
  if (std::abs(value) > kTurn + std::min(halfUnit(col), 0.5)) {
    fail("angle " + quotedField(fields_[col]) + " rad in " + columnName(col) + " is more than a turn (2 pi)");
  }
  return value;
}

int TextTable::integer(std::size_t col) const {
  const std::string_view f = fields_[col];
  int value = 0;
  const auto res = std::from_chars(f.data(), f.data() + f.size(), value);
  if (res.ec != std::errc() || res.ptr != f.data() + f.size()) {
    fail("bad integer " + quotedField(f) + " in " + columnName(col));
  }
  return value;
}

long long TextTable::index(std::size_t col) const {
  const std::string_view f = fields_[col];
  long long value = 0;
  const auto res = std::from_chars(f.data(), f.data() + f.size(), value);
  if (res.ec != std::errc() || res.ptr != f.data() + f.size() || value < 0) {
    fail("bad id " + quotedField(f) + " in " + columnName(col) + " (expected an integer >= 0)");
  }
  return value;
}

double TextTable::halfUnit(std::size_t col) const {
  const std::string_view f = fields_[col];
  const std::size_t e = f.find_first_of("eE");
  const std::string_view mantissa = f.substr(0, e);
  const std::size_t dot = mantissa.find('.');
  long decimals = dot == std::string_view::npos ? 0 : static_cast<long>(mantissa.size() - dot - 1);
  if (e != std::string_view::npos) {
    std::string_view exponent = f.substr(e + 1);
    if (!exponent.empty() && exponent[0] == '+') exponent.remove_prefix(1);
    long x = 0;
    const auto res = std::from_chars(exponent.data(), exponent.data() + exponent.size(), x);
    if (res.ec != std::errc() || res.ptr != exponent.data() + exponent.size()) {
      fail("bad number " + quotedField(f) + " in " + columnName(col));
    }
    decimals -= std::clamp(x, -100000L, 100000L);
  }
  return 0.5 * std::pow(10.0, -static_cast<double>(decimals));
}

void TextTable::fail(const std::string& what) const { throw DataError(name_, line_, what); }

void TimeOrder::check(const TextTable& table, double time) {
  if (time < previous_) {
    table.fail("time " + formatDouble(time) + " goes backwards (line " +
               std::to_string(previous_line_) + " has " + formatDouble(previous_) + ")");
  }
  previous_ = time;
  previous_line_ = table.line();
}

}  // namespace seif
