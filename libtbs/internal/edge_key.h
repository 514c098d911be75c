#pragma once
// A 64-bit key for the undirected edge (a, b) of a triangulation: the smaller index in the high
// half, so that (a, b) and (b, a) have the same key.

#include <algorithm>
#include <cstdint>

namespace tbs::detail {

inline uint64_t edge_key(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(std::min(a, b))) << 32) |
         static_cast<uint32_t>(std::max(a, b));
}

}  // namespace tbs::detail
