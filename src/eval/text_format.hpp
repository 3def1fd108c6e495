#pragma once
// printf onto a std::string: the reports the CLI prints are built as text in the library,
// so that Python gets the same (runSummary, benchSummaryText).
#include <cstdarg>
#include <cstdio>
#include <string>

namespace seif {

[[gnu::format(printf, 2, 0)]] inline void vappendf(std::string& text, const char* format, std::va_list args) {
  std::va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  if (n > 0) {
    const std::size_t at = text.size();
    text.resize(at + static_cast<std::size_t>(n) + 1);
    std::vsnprintf(text.data() + at, static_cast<std::size_t>(n) + 1, format, again);
    text.resize(at + static_cast<std::size_t>(n));
  }
  va_end(again);
}

/// Appends printf(format, ...) to `text`.
[[gnu::format(printf, 2, 3)]] inline void appendf(std::string& text, const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  vappendf(text, format, args);
  va_end(args);
}

/// printf(format, ...) as a string.
[[gnu::format(printf, 1, 2)]] inline std::string formatted(const char* format, ...) {
  std::string text;
  std::va_list args;
  va_start(args, format);
  vappendf(text, format, args);
  va_end(args);
  return text;
}

}  // namespace seif
