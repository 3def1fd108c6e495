#pragma once
// Shared by fuzz_checkpoint and tests/test_checkpoint.cpp: a checkpoint whose header's
// payload size and checksum (FNV-1a 64, docs/checkpoints.md) are made to match its bytes
// again, so that a damaged payload reaches the parser instead of the checksum test.
#include <cstdint>
#include <string>

namespace seif::fuzz {

inline std::string resealed(std::string bytes) {
  constexpr std::size_t kHeader = 32;
  if (bytes.size() < kHeader) return bytes;
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::size_t i = kHeader; i < bytes.size(); ++i) {
    h ^= static_cast<unsigned char>(bytes[i]);
    h *= 0x100000001b3ull;
  }
  const std::uint64_t size = bytes.size() - kHeader;
  for (std::size_t i = 0; i < 8; ++i) {
    bytes[16 + i] = static_cast<char>((size >> (8 * i)) & 0xFF);
    bytes[24 + i] = static_cast<char>((h >> (8 * i)) & 0xFF);
  }
  return bytes;
}

}  // namespace seif::fuzz
