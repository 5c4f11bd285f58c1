// LEMON's maximum-weight perfect matching behind a plain interface. LEMON 1.3's maps call
// std::allocator::construct, removed in C++20, so its headers are compiled in this one C++17 translation unit.
#pragma once

#include <array>
#include <vector>

namespace polysquare::lemon_bridge {

/// Maximum-weight perfect matching of a graph with `nodes` nodes and the given edges and weights. Returns false
/// when no perfect matching exists; otherwise `matched` gets the indices of the matched edges, ascending.
bool max_weight_perfect_matching(int nodes, const std::vector<std::array<int, 2>>& edges,
                                 const std::vector<double>& weights, std::vector<int>& matched);

/// The nodes a maximum-cardinality matching leaves unmatched (empty when a perfect matching exists), ascending.
std::vector<int> unmatched_nodes(int nodes, const std::vector<std::array<int, 2>>& edges);

}  // namespace polysquare::lemon_bridge
