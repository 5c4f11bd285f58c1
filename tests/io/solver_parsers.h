// Parsers of solver files for the tests, written from the formats' documentation, not from our writers:
// SCHISM hgrid.gr3 (SCHISM manual, "hgrid.gr3": header, NE NP, nodes "id x y depth", elements "id i34 n1..n4",
// then NOPE, NETA, per open boundary its node count and nodes, NBOU, NVEL, per land boundary "count flag" and its
// nodes) and SMS 2dm (cards MESH2D, E4Q id n1..n4 mat, ND id x y z, NS node ids with the last one negative, then optionally the nodestring's name).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <utility>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "polysquare/core/geometry.h"
#include "polysquare/core/quad_mesh.h"

namespace polysquare::test {

// A per-process scratch directory under the system's temporary directory, removed when the test process ends
// (the file-writing tests would otherwise leave one behind per run).
inline std::filesystem::path scratch_file(const std::string& prefix, const std::string& name) {
  struct Dir {
    std::filesystem::path path;
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir{std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()))};
  std::filesystem::create_directories(dir.path);
  return dir.path / name;
}

// ---- SCHISM hgrid.gr3, parsed from the format's description ----
struct Gr3 {
  std::string header;
  std::vector<Vec2> xy;
  std::vector<double> depth;
  std::vector<std::vector<std::int32_t>> elements;  // 1-based as in the file
  std::vector<std::vector<std::int32_t>> open;
  std::vector<std::vector<std::int32_t>> land;
  std::vector<int> land_flag;
  long neta = -1, nvel = -1;
};
// The leading integer of a line ("12 = Number of open boundaries" -> 12).
inline long leading(std::istream& in, std::string* rest = nullptr) {
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error("gr3: truncated");
  std::istringstream ls(line);
  long v = 0;
  if (!(ls >> v)) throw std::runtime_error("gr3: expected a number in '" + line + "'");
  if (rest) std::getline(ls, *rest);
  return v;
}
inline Gr3 parse_gr3(const std::filesystem::path& p) {
  std::ifstream in(p);
  Gr3 g;
  std::getline(in, g.header);
  long ne = 0, np = 0;
  in >> ne >> np;
  for (long i = 0; i < np; ++i) {
    long id = 0;
    std::string x, y, d;
    in >> id >> x >> y >> d;
    if (id != i + 1) throw std::runtime_error("gr3: node ids out of order");
    g.xy.push_back({std::strtod(x.c_str(), nullptr), std::strtod(y.c_str(), nullptr)});
    g.depth.push_back(std::strtod(d.c_str(), nullptr));
  }
  for (long i = 0; i < ne; ++i) {
    long id = 0, i34 = 0;
    in >> id >> i34;
    std::vector<std::int32_t> e(static_cast<std::size_t>(i34));
    for (auto& v : e) in >> v;
    if (id != i + 1) throw std::runtime_error("gr3: element ids out of order");
    g.elements.push_back(e);
  }
  std::string rest;
  std::getline(in, rest);  // end of the last element line
  const long nope = leading(in);
  g.neta = leading(in);
  for (long k = 0; k < nope; ++k) {
    std::vector<std::int32_t> seg(static_cast<std::size_t>(leading(in)));
    for (auto& v : seg) v = static_cast<std::int32_t>(leading(in));
    g.open.push_back(seg);
  }
  const long nbou = leading(in);
  g.nvel = leading(in);
  for (long k = 0; k < nbou; ++k) {
    const long count = leading(in, &rest);
    std::istringstream flag(rest);
    int f = -1;
    flag >> f;
    std::vector<std::int32_t> seg(static_cast<std::size_t>(count));
    for (auto& v : seg) v = static_cast<std::int32_t>(leading(in));
    g.land.push_back(seg);
    g.land_flag.push_back(f);
  }
  return g;
}

// ---- SMS 2dm ----
struct Sms {
  std::map<long, Vec2> nodes;
  std::map<long, double> z;
  std::map<long, std::vector<long>> e4q;
  std::vector<std::vector<long>> strings;
  std::vector<std::string> string_names;  ///< per string: what follows its negative last id ("" when nothing)
  bool mesh2d = false;
};
inline Sms parse_2dm(const std::filesystem::path& p) {
  std::ifstream in(p);
  Sms s;
  std::string line;
  std::vector<long> current;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string card;
    ls >> card;
    if (card == "MESH2D") s.mesh2d = true;
    if (card == "ND") {
      long id = 0;
      std::string x, y, z;
      ls >> id >> x >> y >> z;
      s.nodes[id] = {std::strtod(x.c_str(), nullptr), std::strtod(y.c_str(), nullptr)};
      s.z[id] = std::strtod(z.c_str(), nullptr);
    }
    if (card == "E4Q") {
      long id = 0;
      std::vector<long> n(4);
      ls >> id >> n[0] >> n[1] >> n[2] >> n[3];
      s.e4q[id] = n;
    }
    if (card == "NS") {
      long v = 0;
      while (ls >> v) {
        current.push_back(std::abs(v));
        if (v < 0) {
          s.strings.push_back(current);
          current.clear();
          std::string name;
          std::getline(ls >> std::ws, name);
          s.string_names.push_back(name);
          break;
        }
      }
    }
  }
  if (!current.empty()) throw std::runtime_error("2dm: a nodestring without its negative last node");
  return s;
}

// ---- mesh edges, for comparing the files' boundaries with the mesh ----
using Edge = std::pair<std::int32_t, std::int32_t>;  // 0-based, sorted
inline Edge sorted(std::int32_t a, std::int32_t b) { return {std::min(a, b), std::max(a, b)}; }

// Edges of one quad, computed here from the quads alone.
inline std::set<Edge> one_quad_edges(const QuadMesh& m) {
  std::map<Edge, int> count;
  for (const auto& q : m.quads)
    for (int k = 0; k < 4; ++k) count[sorted(q[k], q[(k + 1) % 4])]++;
  std::set<Edge> out;
  for (const auto& [e, c] : count)
    if (c == 1) out.insert(e);
  return out;
}

}  // namespace polysquare::test
