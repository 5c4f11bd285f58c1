#include "fallback/perfect_matching.h"

#include <lemon/list_graph.h>
#include <algorithm>
#include <lemon/matching.h>

namespace polysquare::lemon_bridge {

bool max_weight_perfect_matching(int nodes, const std::vector<std::array<int, 2>>& edges,
                                 const std::vector<double>& weights, std::vector<int>& matched) {
  lemon::ListGraph g;
  std::vector<lemon::ListGraph::Node> node;
  node.reserve(static_cast<std::size_t>(nodes));
  for (int i = 0; i < nodes; ++i) node.push_back(g.addNode());
  lemon::ListGraph::EdgeMap<double> weight(g);
  lemon::ListGraph::EdgeMap<int> index(g);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto edge = g.addEdge(node[static_cast<std::size_t>(edges[e][0])], node[static_cast<std::size_t>(edges[e][1])]);
    weight[edge] = weights[e];
    index[edge] = static_cast<int>(e);
  }
  lemon::MaxWeightedPerfectMatching<lemon::ListGraph, lemon::ListGraph::EdgeMap<double>> matching(g, weight);
  if (!matching.run()) return false;
  matched.clear();
  for (lemon::ListGraph::EdgeIt e(g); e != lemon::INVALID; ++e)
    if (matching.matching(e)) matched.push_back(index[e]);
  std::sort(matched.begin(), matched.end());
  return true;
}

std::vector<int> unmatched_nodes(int nodes, const std::vector<std::array<int, 2>>& edges) {
  lemon::ListGraph g;
  std::vector<lemon::ListGraph::Node> node;
  node.reserve(static_cast<std::size_t>(nodes));
  for (int i = 0; i < nodes; ++i) node.push_back(g.addNode());
  for (const auto& e : edges) g.addEdge(node[static_cast<std::size_t>(e[0])], node[static_cast<std::size_t>(e[1])]);
  lemon::MaxMatching<lemon::ListGraph> matching(g);
  matching.run();
  std::vector<int> out;
  for (int i = 0; i < nodes; ++i)
    if (matching.mate(node[static_cast<std::size_t>(i)]) == lemon::INVALID) out.push_back(i);
  return out;
}

}  // namespace polysquare::lemon_bridge
