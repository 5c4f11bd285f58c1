// Gmsh MSH reader (2.2 and 4.1, ASCII and binary little-endian) and writer (2.2 and 4.1).
#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include "crs_info.h"
#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"

namespace polysquare {
namespace {

// Cursor over the file bytes: tokens for ASCII sections, raw values for binary ones; every read is bounded.
struct Cursor {
  const std::string& data;
  const std::string& name;
  std::size_t pos = 0;
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(name + ": " + what + " at byte " + std::to_string(pos));
  }
  std::string token() {
    while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    if (pos >= data.size()) fail("unexpected end of file");
    const std::size_t start = pos;
    while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    return data.substr(start, pos - start);
  }
  long long integer() {
    const std::string t = token();
    try { std::size_t used = 0; const long long v = std::stoll(t, &used); if (used == t.size()) return v; } catch (...) {}
    fail("expected an integer, got '" + t.substr(0, 20) + "'");
  }
  double real() {
    const std::string t = token();
    try { std::size_t used = 0; const double v = std::stod(t, &used); if (used == t.size()) return v; } catch (...) {}
    fail("expected a number, got '" + t.substr(0, 20) + "'");
  }
  template <typename T> T raw() {
    if (pos + sizeof(T) > data.size()) fail("unexpected end of binary data");
    T v;
    std::memcpy(&v, data.data() + pos, sizeof(T));
    pos += sizeof(T);
    return v;
  }
  void skip_line() {
    while (pos < data.size() && data[pos] != '\n') ++pos;
    if (pos < data.size()) ++pos;
  }
  void expect(const std::string& word) {
    const std::string t = token();
    if (t != word) fail("expected " + word + ", got '" + t.substr(0, 30) + "'");
  }
  std::size_t count(long long v, std::size_t min_bytes_each) {
    if (v < 0 || static_cast<unsigned long long>(v) > (data.size() - std::min(pos, data.size())) / min_bytes_each + 1)
      fail("count " + std::to_string(v) + " does not fit in the file");
    return static_cast<std::size_t>(v);
  }
};

struct Builder {
  QuadMesh mesh;
  std::unordered_map<long long, std::int32_t> node_index;
  std::map<int, std::string> physical_names[2];  // per dimension 0 and 1: tag -> name
  std::map<int, int> entity_physical[2];         // 4.1, per dimension 0 and 1: entity tag -> physical tag
  std::map<std::string, int> curve_ids;          // "boundary"/"feature" name -> ring or curve index
  std::map<std::string, std::vector<std::int32_t>> feature_points;  // "feature*" point group -> its nodes
  void node(long long tag, double x, double y) {
    node_index[tag] = static_cast<std::int32_t>(mesh.nodes.size());
    mesh.nodes.push_back({x, y});
  }
  std::int32_t at(long long tag, const Cursor& c) const {
    auto it = node_index.find(tag);
    if (it == node_index.end()) c.fail("element refers to unknown node " + std::to_string(tag));
    return it->second;
  }
  // The index our writer put after the last '_' ("boundary_ring_3" -> 3), so files round-trip; other names get
  // the next free index.
  int curve_id(const std::string& name) {
    auto it = curve_ids.find(name);
    if (it != curve_ids.end()) return it->second;
    int id = -1;
    const std::size_t cut = name.rfind('_');
    if (cut != std::string::npos && cut + 1 < name.size() && cut + 7 > name.size() &&
        name.find_first_not_of("0123456789", cut + 1) == std::string::npos)
      id = std::stoi(name.substr(cut + 1));
    const bool boundary = name.rfind("boundary", 0) == 0;
    for (const auto& [other, used] : curve_ids)
      if (used == id && (other.rfind("boundary", 0) == 0) == boundary) id = -1;
    if (id < 0) {
      id = 0;
      for (const auto& [other, used] : curve_ids)
        if ((other.rfind("boundary", 0) == 0) == boundary) id = std::max(id, used + 1);
    }
    return curve_ids[name] = id;
  }
  void element(int type, int physical, const std::vector<long long>& nodes, const Cursor& c) {
    if (type == 3) mesh.quads.push_back({at(nodes[0], c), at(nodes[1], c), at(nodes[2], c), at(nodes[3], c)});
    else if (type == 2) mesh.triangles.push_back({at(nodes[0], c), at(nodes[1], c), at(nodes[2], c)});
    else if (type == 15) {
      auto it = physical_names[0].find(physical);
      // Every named point group is a curve's nodes (polysquare writes named features that way).
      if (it != physical_names[0].end()) feature_points[it->second].push_back(at(nodes[0], c));
    } else if (type == 1) {
      auto it = physical_names[1].find(physical);
      if (it == physical_names[1].end()) return;
      const std::string& n = it->second;
      const std::array<std::int32_t, 2> e{at(nodes[0], c), at(nodes[1], c)};
      const int id = curve_id(n);
      if (n.rfind("boundary", 0) == 0) { mesh.boundary_edges.push_back(e); mesh.boundary_edge_ring.push_back(id); }
      else if (n.rfind("feature", 0) == 0) { mesh.feature_edges.push_back(e); mesh.feature_edge_curve.push_back(id); }
      else other_lines[n].push_back(e);
    } else if (type == 4 || type == 5) {  // skipping them would judge what is left of a 3D mesh
      c.fail(std::string("a 3D element (") + (type == 4 ? "tetrahedron" : "hexahedron") +
             "); only 2D meshes of triangles and quadrilaterals are read");
    } else if (type == 9 || type == 10) {
      c.fail(std::string("a second-order ") + (type == 9 ? "triangle" : "quadrilateral") +
             " (element type " + std::to_string(type) + "); only linear triangles and quadrilaterals are read");
    }
  }
  // Lines of other names (named boundary segments, named features): boundary edges where one cell has the
  // edge, feature edges where two do; each name its own ring or curve index after those read.
  std::map<std::string, std::vector<std::array<std::int32_t, 2>>> other_lines;
  void classify_other_lines() {
    if (other_lines.empty()) return;
    std::unordered_map<std::uint64_t, int> cells;
    auto key = [](std::int32_t a, std::int32_t b) {
      return static_cast<std::uint64_t>(std::min(a, b)) << 32 | static_cast<std::uint64_t>(std::max(a, b));
    };
    for (const auto& q : mesh.quads)
      for (int k = 0; k < 4; ++k) cells[key(q[k], q[(k + 1) % 4])]++;
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) cells[key(t[k], t[(k + 1) % 3])]++;
    int ring = 0, curve = 0;
    for (auto r : mesh.boundary_edge_ring) ring = std::max(ring, r + 1);
    for (auto f : mesh.feature_edge_curve) curve = std::max(curve, f + 1);
    for (const auto& [name, edges] : other_lines) {
      bool any_boundary = false, any_feature = false;
      for (const auto& e : edges) {
        const auto it = cells.find(key(e[0], e[1]));
        if (it != cells.end() && it->second == 1) { mesh.boundary_edges.push_back(e); mesh.boundary_edge_ring.push_back(ring); any_boundary = true; }
        else { mesh.feature_edges.push_back(e); mesh.feature_edge_curve.push_back(curve); any_feature = true; }
      }
      ring += any_boundary;
      curve += any_feature;
    }
  }
  // A curve written as a point group becomes the cell edges joining two of its nodes (a group that also has
  // line elements keeps those). One pass over the cell edges, each looked up in the groups of its two ends.
  void feature_edges_from_points() {
    std::unordered_map<std::int32_t, std::vector<int>> groups_of;
    for (const auto& [name, nodes] : feature_points) {
      if (curve_ids.count(name)) continue;
      const int id = curve_id(name);
      for (auto v : nodes) {
        auto& g = groups_of[v];
        if (std::find(g.begin(), g.end(), id) == g.end()) g.push_back(id);
      }
    }
    if (groups_of.empty()) return;
    std::unordered_map<std::uint64_t, bool> seen;
    auto edge = [&](std::int32_t a, std::int32_t b) {
      auto ia = groups_of.find(a), ib = groups_of.find(b);
      if (ia == groups_of.end() || ib == groups_of.end()) return;
      const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
      if (!seen.emplace(lo << 32 | hi, true).second) return;
      for (int g : ia->second)
        if (std::find(ib->second.begin(), ib->second.end(), g) != ib->second.end()) {
          mesh.feature_edges.push_back({a, b});
          mesh.feature_edge_curve.push_back(g);
        }
    };
    for (const auto& q : mesh.quads)
      for (int k = 0; k < 4; ++k) edge(q[k], q[(k + 1) % 4]);
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) edge(t[k], t[(k + 1) % 3]);
  }
};

int nodes_per_element(int type, const Cursor& c) {
  switch (type) {
    case 1: return 2;
    case 2: return 3;
    case 3: return 4;
    case 15: return 1;
    case 4: return 4;
    case 5: return 8;
    case 8: return 3;
    case 9: return 6;
    case 10: return 9;
    default: c.fail("unsupported element type " + std::to_string(type));
  }
}

void read_physical_names(Cursor& c, Builder& b) {
  const std::size_t n = c.count(c.integer(), 4);
  for (std::size_t i = 0; i < n; ++i) {
    const long long dim = c.integer(), tag = c.integer();
    std::string name = c.token();
    while (name.size() < 2 || name.back() != '"') {
      if (name.size() > 1000) c.fail("unterminated physical name");
      name += " " + c.token();
    }
    if (dim == 0 || dim == 1) b.physical_names[dim][static_cast<int>(tag)] = name.substr(1, name.size() - 2);
  }
  c.expect("$EndPhysicalNames");
}

// $Comments ... $EndComments (Gmsh ignores sections it does not know; our writer keeps the CRS there): skipped
// as text whatever it holds, its "crs VALUE" line read into the mesh.
void read_comments(Cursor& c, Builder& b) {
  const std::size_t end = c.data.find("\n$EndComments", c.pos);
  if (end == std::string::npos) c.fail("$Comments without $EndComments");
  std::istringstream lines(c.data.substr(c.pos, end - c.pos));
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind("crs ", 0) == 0) b.mesh.crs = line.substr(4);
  }
  c.pos = end + 1;
  c.expect("$EndComments");
}

void read_v2(Cursor& c, Builder& b, bool binary) {
  while (c.pos < c.data.size()) {
    std::string section;
    try { section = c.token(); } catch (const InputError&) { break; }
    if (section == "$PhysicalNames") read_physical_names(c, b);
    else if (section == "$Comments") read_comments(c, b);
    else if (section == "$Nodes") {
      const std::size_t n = c.count(c.integer(), binary ? 28 : 8);
      if (binary) c.skip_line();
      for (std::size_t i = 0; i < n; ++i) {
        if (binary) { const int tag = c.raw<int>(); const double x = c.raw<double>(), y = c.raw<double>(); c.raw<double>(); b.node(tag, x, y); }
        else { const long long tag = c.integer(); const double x = c.real(), y = c.real(); c.real(); b.node(tag, x, y); }
      }
      c.expect("$EndNodes");
    } else if (section == "$Elements") {
      const std::size_t n = c.count(c.integer(), binary ? 12 : 6);
      if (binary) c.skip_line();
      std::vector<long long> nodes;
      for (std::size_t done = 0; done < n;) {
        if (binary) {
          const int type = c.raw<int>(), count = c.raw<int>(), ntags = c.raw<int>();
          if (count <= 0 || ntags < 0 || ntags > 100 || static_cast<std::size_t>(count) > n - done) c.fail("bad element block");
          const int nn = nodes_per_element(type, c);
          for (int k = 0; k < count; ++k) {
            c.raw<int>();
            int physical = 0;
            for (int t = 0; t < ntags; ++t) { const int v = c.raw<int>(); if (t == 0) physical = v; }
            nodes.assign(static_cast<std::size_t>(nn), 0);
            for (auto& v : nodes) v = c.raw<int>();
            b.element(type, physical, nodes, c);
          }
          done += static_cast<std::size_t>(count);
        } else {
          c.integer();
          const int type = static_cast<int>(c.integer());
          const long long ntags = c.integer();
          if (ntags < 0 || ntags > 100) c.fail("bad tag count");
          int physical = 0;
          for (long long t = 0; t < ntags; ++t) { const long long v = c.integer(); if (t == 0) physical = static_cast<int>(v); }
          nodes.assign(static_cast<std::size_t>(nodes_per_element(type, c)), 0);
          for (auto& v : nodes) v = c.integer();
          b.element(type, physical, nodes, c);
          ++done;
        }
      }
      c.expect("$EndElements");
    }
  }
}

void read_v4(Cursor& c, Builder& b, bool binary) {
  auto size = [&]() -> long long { return binary ? static_cast<long long>(c.raw<std::uint64_t>()) : c.integer(); };
  auto i32 = [&]() -> int { return binary ? c.raw<int>() : static_cast<int>(c.integer()); };
  auto f64 = [&]() -> double { return binary ? c.raw<double>() : c.real(); };
  while (c.pos < c.data.size()) {
    std::string section;
    try { section = c.token(); } catch (const InputError&) { break; }
    if (binary && section.rfind("$End", 0) != 0 && section[0] == '$') c.skip_line();
    if (section == "$PhysicalNames") {
      if (binary) c.pos -= 0;  // PhysicalNames is ASCII in both forms
      read_physical_names(c, b);
    } else if (section == "$Comments") {
      if (binary) c.pos -= 1;  // the line break skipped above: the section's text starts after it
      read_comments(c, b);
    } else if (section == "$Entities") {
      const long long np = size(), nc = size(), ns = size(), nv = size();
      for (long long i = 0; i < np; ++i) {
        const int tag = i32();
        for (int k = 0; k < 3; ++k) f64();
        const std::size_t nphys = c.count(size(), 4);
        for (std::size_t k = 0; k < nphys; ++k) { const int p = i32(); if (k == 0) b.entity_physical[0][tag] = p; }
      }
      for (long long dim = 1; dim <= 3; ++dim) {
        const long long n = dim == 1 ? nc : (dim == 2 ? ns : nv);
        for (long long i = 0; i < n; ++i) {
          const int tag = i32();
          for (int k = 0; k < 6; ++k) f64();
          const std::size_t nphys = c.count(size(), 4);
          for (std::size_t k = 0; k < nphys; ++k) { const int p = i32(); if (dim == 1 && k == 0) b.entity_physical[1][tag] = p; }
          const std::size_t nb = c.count(size(), 4);
          for (std::size_t k = 0; k < nb; ++k) i32();
        }
      }
      c.expect("$EndEntities");
    } else if (section == "$Nodes") {
      const long long blocks = size();
      const std::size_t total = c.count(size(), binary ? 24 : 4);
      size(); size();
      (void)total;
      for (long long bl = 0; bl < blocks; ++bl) {
        i32(); i32();
        const int parametric = i32();
        const std::size_t n = c.count(size(), 8);
        std::vector<long long> tags(n);
        for (auto& t : tags) t = size();
        for (std::size_t i = 0; i < n; ++i) {
          const double x = f64(), y = f64();
          f64();
          if (parametric) c.fail("parametric nodes are not supported");
          b.node(tags[i], x, y);
        }
      }
      c.expect("$EndNodes");
    } else if (section == "$Elements") {
      const long long blocks = size();
      c.count(size(), 8);
      size(); size();
      std::vector<long long> nodes;
      for (long long bl = 0; bl < blocks; ++bl) {
        const int dim = i32(), entity = i32(), type = i32();
        const std::size_t n = c.count(size(), 8);
        const int nn = nodes_per_element(type, c);
        int physical = 0;
        if (dim == 0 || dim == 1) {
          auto it = b.entity_physical[dim].find(entity);
          if (it != b.entity_physical[dim].end()) physical = it->second;
        }
        for (std::size_t i = 0; i < n; ++i) {
          size();
          nodes.assign(static_cast<std::size_t>(nn), 0);
          for (auto& v : nodes) v = size();
          b.element(type, physical, nodes, c);
        }
      }
      c.expect("$EndElements");
    }
  }
}

}  // namespace

QuadMesh read_msh(const std::filesystem::path& path) { return parse_msh(read_file(path), path.string()); }

QuadMesh parse_msh(const std::string& data, const std::string& name) {
  Cursor c{data, name};
  c.expect("$MeshFormat");
  const std::string version = c.token();
  const long long file_type = c.integer();
  const long long data_size = c.integer();
  if (file_type != 0 && file_type != 1) c.fail("unknown file type");
  const bool binary = file_type == 1;
  if (binary) {
    c.skip_line();
    if (data_size != 8) c.fail("binary MSH with data size " + std::to_string(data_size) + " is not supported");
    if (c.raw<int>() != 1) c.fail("binary MSH in big-endian byte order is not supported");
  }
  c.expect("$EndMeshFormat");
  Builder b;
  if (version.rfind("2.", 0) == 0) read_v2(c, b, binary);
  else if (version.rfind("4.", 0) == 0) read_v4(c, b, binary);
  else c.fail("unsupported MSH version " + version);
  if (b.mesh.quads.empty() && b.mesh.triangles.empty()) throw InputError(name + ": the mesh has no quads or triangles");
  b.classify_other_lines();
  b.feature_edges_from_points();
  return std::move(b.mesh);
}

namespace {

// What goes into the file besides the quads: one physical group (and one entity) per boundary ring and per
// feature curve, lines or points.
struct Group {
  int dim = 1;      // 1: line elements, 0: point elements
  int entity = 0;   // entity (elementary) tag, counted per dimension from 1
  int physical = 0;
  std::string name;
  std::vector<std::array<std::int32_t, 2>> lines;
  std::vector<std::int32_t> points;
  Box2 box;
};

std::vector<Group> msh_groups(const QuadMesh& mesh, const MeshGroups& named, MshFeatures features) {
  std::vector<Group> groups;
  int entities[2] = {0, 0};
  // Physical tags come from the named groups and do not depend on the feature mode, so boundary ids stay the
  // same in every file. Empty groups (a ring wholly covered by segments) are left out, their tags unused.
  auto add = [&](const CurveGroup& c, int dim) {
    if (c.edges.empty()) return;
    Group g;
    g.dim = dim;
    g.entity = ++entities[dim];
    g.physical = c.tag;
    g.name = c.name;
    for (const auto& e : c.edges) g.box.add(mesh.nodes[e[0]]), g.box.add(mesh.nodes[e[1]]);
    if (dim == 1) g.lines = c.edges;
    else {
      std::unordered_map<std::int32_t, bool> seen;
      for (const auto& e : c.edges)
        for (auto v : e)
          if (seen.emplace(v, true).second) g.points.push_back(v);
    }
    groups.push_back(std::move(g));
  };
  for (const CurveGroup& c : named.rings) add(c, 1);
  if (features != MshFeatures::none)
    for (const CurveGroup& c : named.features) add(c, features == MshFeatures::lines ? 1 : 0);
  for (const CurveGroup& c : named.segments) add(c, 1);
  return groups;
}

// ASCII or little-endian binary values in the layout both MSH versions share.
struct MshStream {
  std::ostream& os;
  bool bin;
  void size(std::uint64_t v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 8); else os << v; }
  void i32(int v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 4); else os << v; }
  void f64(double v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 8); else os << v; }
  void sep(const char* s) { if (!bin) os << s; }
  void end_binary() { if (bin) os << "\n"; }
};

// Physical names are quoted strings on one line: quotes and line breaks in an input name become '_'.
std::string physical_name(std::string name) {
  for (char& ch : name)
    if (ch == '"' || ch == '\n' || ch == '\r') ch = '_';
  return name;
}

// The CRS of the coordinates, where other readers pass it by: a $Comments section after $EndElements (the Gmsh
// manual: a reader skips a section whose header it does not know, $Comments/$EndComments being its example of a
// place for comments; deal.II's reader stops at $EndElements). One "key value" line
// each: crs (as recorded, e.g. EPSG:32616), crs_name, crs_epsg (0 when no EPSG code is identified), crs_wkt (one
// line). No line starts with '$', so no reader ends the section early.
void write_crs_comments(std::ostream& os, const std::string& crs) {
  if (crs.empty()) return;
  auto one_line = [](std::string text) {
    for (char& ch : text)
      if (ch == '\n' || ch == '\r') ch = ' ';
    return text;
  };
  const crs::CrsInfo info = crs::crs_info(crs);
  os << "$Comments\ncrs " << one_line(crs) << "\n";
  if (info.known) {
    os << "crs_name " << one_line(info.name) << "\ncrs_epsg " << info.epsg << "\n";
    if (!info.wkt.empty()) os << "crs_wkt " << one_line(info.wkt) << "\n";
  }
  os << "$EndComments\n";
}

void write_physical_names(std::ostream& os, const std::vector<SurfaceGroup>& surfaces, const std::vector<Group>& groups) {
  os << "$PhysicalNames\n" << groups.size() + surfaces.size() << "\n";
  for (const SurfaceGroup& s : surfaces) os << "2 " << s.tag << " \"" << physical_name(s.name) << "\"\n";
  for (const Group& g : groups) os << g.dim << " " << g.physical << " \"" << physical_name(g.name) << "\"\n";
  os << "$EndPhysicalNames\n";
}

void write_v41(MshStream& w, const QuadMesh& mesh, const std::vector<SurfaceGroup>& surfaces, const std::vector<Group>& groups) {
  std::ostream& os = w.os;
  Box2 all;
  for (Vec2 p : mesh.nodes) all.add(p);
  std::size_t count[2] = {0, 0};
  for (const Group& g : groups) count[g.dim]++;
  os << "$Entities\n";
  w.size(count[0]); w.sep(" "); w.size(count[1]); w.sep(" "); w.size(surfaces.size()); w.sep(" "); w.size(0); w.sep("\n");
  auto bbox = [&](const Box2& b) {
    for (double v : {b.lo.x, b.lo.y, 0.0, b.hi.x, b.hi.y, 0.0}) { w.f64(v); w.sep(" "); }
  };
  for (int dim : {0, 1})
    for (const Group& g : groups) {
      if (g.dim != dim) continue;
      w.i32(g.entity); w.sep(" ");
      if (dim == 0) {  // a point entity has one position: the group's first node
        const Vec2 p = mesh.nodes[g.points.front()];
        w.f64(p.x); w.sep(" "); w.f64(p.y); w.sep(" "); w.f64(0); w.sep(" ");
      } else {
        bbox(g.box);
      }
      w.size(1); w.sep(" "); w.i32(g.physical); w.sep(" ");
      if (dim == 1) { w.size(0); w.sep(" "); }
      w.sep("\n");
    }
  for (std::size_t k = 0; k < surfaces.size(); ++k) {  // surface entity k + 1 holds surface group k
    Box2 box;
    for (auto q : surfaces[k].quads)
      for (auto v : mesh.quads[static_cast<std::size_t>(q)]) box.add(mesh.nodes[static_cast<std::size_t>(v)]);
    if (surfaces.size() == 1) box = all;
    w.i32(static_cast<int>(k + 1)); w.sep(" "); bbox(box); w.size(1); w.sep(" "); w.i32(surfaces[k].tag); w.sep(" ");
    w.size(0); w.sep("\n");
  }
  w.end_binary();
  os << "$EndEntities\n$Nodes\n";
  const std::uint64_t nn = mesh.nodes.size();
  w.size(1); w.sep(" "); w.size(nn); w.sep(" "); w.size(1); w.sep(" "); w.size(nn); w.sep("\n");
  w.i32(2); w.sep(" "); w.i32(1); w.sep(" "); w.i32(0); w.sep(" "); w.size(nn); w.sep("\n");
  for (std::uint64_t v = 1; v <= nn; ++v) { w.size(v); w.sep("\n"); }
  for (Vec2 p : mesh.nodes) { w.f64(p.x); w.sep(" "); w.f64(p.y); w.sep(" "); w.f64(0); w.sep("\n"); }
  w.end_binary();
  os << "$EndNodes\n$Elements\n";
  std::uint64_t nel = mesh.quads.size();
  for (const Group& g : groups) nel += g.lines.size() + g.points.size();
  w.size(groups.size() + surfaces.size()); w.sep(" "); w.size(nel); w.sep(" "); w.size(1); w.sep(" "); w.size(nel); w.sep("\n");
  std::uint64_t tag = 1;
  auto node = [&](std::int32_t v) { w.sep(" "); w.size(static_cast<std::uint64_t>(v) + 1); };
  for (const Group& g : groups) {
    w.i32(g.dim); w.sep(" "); w.i32(g.entity); w.sep(" "); w.i32(g.dim == 1 ? 1 : 15); w.sep(" ");
    w.size(g.lines.size() + g.points.size()); w.sep("\n");
    for (const auto& e : g.lines) { w.size(tag++); node(e[0]); node(e[1]); w.sep("\n"); }
    for (auto v : g.points) { w.size(tag++); node(v); w.sep("\n"); }
  }
  for (std::size_t k = 0; k < surfaces.size(); ++k) {
    w.i32(2); w.sep(" "); w.i32(static_cast<int>(k + 1)); w.sep(" "); w.i32(3); w.sep(" "); w.size(surfaces[k].quads.size()); w.sep("\n");
    for (auto q : surfaces[k].quads) {
      w.size(tag++);
      for (auto v : mesh.quads[static_cast<std::size_t>(q)]) node(v);
      w.sep("\n");
    }
  }
  w.end_binary();
  os << "$EndElements\n";
}

// MSH 2.2: no entities; every element carries its physical and elementary tags. Binary element blocks start with
// (type, count, number of tags), and every value is a 32-bit int.
void write_v22(MshStream& w, const QuadMesh& mesh, const std::vector<SurfaceGroup>& surfaces, const std::vector<Group>& groups) {
  std::ostream& os = w.os;
  constexpr auto most = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 2);
  if (mesh.nodes.size() >= most || mesh.quads.size() >= most)
    throw InputError("MSH 2.2 numbers nodes and elements with 32-bit integers: the mesh is too large, use MSH 4.1");
  os << "$Nodes\n" << mesh.nodes.size() << "\n";
  int id = 1;
  for (Vec2 p : mesh.nodes) { w.i32(id++); w.sep(" "); w.f64(p.x); w.sep(" "); w.f64(p.y); w.sep(" "); w.f64(0); w.sep("\n"); }
  w.end_binary();
  os << "$EndNodes\n$Elements\n";
  std::size_t nel = mesh.quads.size();
  for (const Group& g : groups) nel += g.lines.size() + g.points.size();
  os << nel << "\n";
  int tag = 1;
  auto block = [&](int type, std::size_t count, int physical, int entity, auto&& each) {
    if (count == 0) return;
    if (w.bin) { w.i32(type); w.i32(static_cast<int>(count)); w.i32(2); }
    each([&](std::initializer_list<std::int32_t> nodes) {
      w.i32(tag++); w.sep(" ");
      if (!w.bin) { w.i32(type); w.sep(" 2 "); }
      w.i32(physical); w.sep(" "); w.i32(entity);
      for (auto v : nodes) { w.sep(" "); w.i32(v + 1); }
      w.sep("\n");
    });
  };
  for (const Group& g : groups) {
    block(1, g.lines.size(), g.physical, g.entity, [&](auto&& put) { for (const auto& e : g.lines) put({e[0], e[1]}); });
    block(15, g.points.size(), g.physical, g.entity, [&](auto&& put) { for (auto v : g.points) put({v}); });
  }
  for (std::size_t k = 0; k < surfaces.size(); ++k)
    block(3, surfaces[k].quads.size(), surfaces[k].tag, static_cast<int>(k + 1), [&](auto&& put) {
      for (auto qi : surfaces[k].quads) {
        const auto& q = mesh.quads[static_cast<std::size_t>(qi)];
        put({q[0], q[1], q[2], q[3]});
      }
    });
  w.end_binary();
  os << "$EndElements\n";
}

}  // namespace

void write_msh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  const MeshGroups named = options.groups.empty() ? mesh_groups(mesh) : options.groups;
  const std::vector<Group> groups = msh_groups(mesh, named, options.msh_features);
  const bool v41 = options.msh_version == MshVersion::v4_1;
  write_file_atomically(path, [&](std::ostream& os) {
    os.precision(17);
    MshStream w{os, options.binary};
    os << "$MeshFormat\n" << (v41 ? "4.1 " : "2.2 ") << (w.bin ? 1 : 0) << " 8\n";
    if (w.bin) { w.i32(1); os << "\n"; }
    os << "$EndMeshFormat\n";
    write_physical_names(os, named.surfaces, groups);
    if (v41) write_v41(w, mesh, named.surfaces, groups);
    else write_v22(w, mesh, named.surfaces, groups);
    write_crs_comments(os, mesh.crs);
  }, options.binary);
}

}  // namespace polysquare
