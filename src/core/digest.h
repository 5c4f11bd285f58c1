// A 128-bit digest (two independent 64-bit lanes) over the 64-bit words of what a computation reads: the key of
// the run's memos (map/deform, map/quantize). Internal to the library.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace polysquare {

struct Digest {
  std::uint64_t a = 0x9e3779b97f4a7c15ull, b = 0x6a09e667f3bcc909ull;
  void word(std::uint64_t w) {
    a = (a ^ w) * 0xff51afd7ed558ccdull;
    a ^= a >> 33;
    b = (b + w) * 0xc4ceb9fe1a85ec53ull;
    b ^= b >> 29;
    b = (b << 21) | (b >> 43);
  }
  void real(double v) {
    std::uint64_t w;
    std::memcpy(&w, &v, sizeof w);
    word(w);
  }
  void bytes(const void* data, std::size_t n) {
    word(n);
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      word(w);
    }
    std::uint64_t tail = 0;
    if (n > i) std::memcpy(&tail, p + i, n - i);  // an empty vector's data() may be null
    word(tail);
  }
  template <typename T>
  void raw(const std::vector<T>& v) {  // types without padding only
    word(v.size());
    bytes(v.data(), v.size() * sizeof(T));
  }
  void text(std::string_view s) { bytes(s.data(), s.size()); }
  std::array<std::uint64_t, 2> key() const { return {a, b}; }
};

}  // namespace polysquare
