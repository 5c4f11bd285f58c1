// Gmsh MSH reader (2.2 and 4.1, ASCII and binary little-endian) and MSH 4.1 writer.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>

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
  std::map<int, std::string> physical_names;  // (tag) -> name, dimension 1 only
  std::map<int, int> curve_entity_physical;   // 4.1: curve entity tag -> physical tag
  std::map<std::string, int> curve_ids;       // "boundary"/"feature" name -> running index
  void node(long long tag, double x, double y) {
    node_index[tag] = static_cast<std::int32_t>(mesh.nodes.size());
    mesh.nodes.push_back({x, y});
  }
  std::int32_t at(long long tag, const Cursor& c) const {
    auto it = node_index.find(tag);
    if (it == node_index.end()) c.fail("element refers to unknown node " + std::to_string(tag));
    return it->second;
  }
  void element(int type, int physical, const std::vector<long long>& nodes, const Cursor& c) {
    if (type == 3) mesh.quads.push_back({at(nodes[0], c), at(nodes[1], c), at(nodes[2], c), at(nodes[3], c)});
    else if (type == 2) mesh.triangles.push_back({at(nodes[0], c), at(nodes[1], c), at(nodes[2], c)});
    else if (type == 1) {
      auto it = physical_names.find(physical);
      if (it == physical_names.end()) return;
      const std::string& n = it->second;
      const std::array<std::int32_t, 2> e{at(nodes[0], c), at(nodes[1], c)};
      const int id = curve_ids.try_emplace(n, static_cast<int>(curve_ids.size())).first->second;
      if (n.rfind("boundary", 0) == 0) { mesh.boundary_edges.push_back(e); mesh.boundary_edge_ring.push_back(id); }
      else if (n.rfind("feature", 0) == 0) { mesh.feature_edges.push_back(e); mesh.feature_edge_curve.push_back(id); }
    }
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
    if (dim == 1) b.physical_names[static_cast<int>(tag)] = name.substr(1, name.size() - 2);
  }
  c.expect("$EndPhysicalNames");
}

void read_v2(Cursor& c, Builder& b, bool binary) {
  while (c.pos < c.data.size()) {
    std::string section;
    try { section = c.token(); } catch (const InputError&) { break; }
    if (section == "$PhysicalNames") read_physical_names(c, b);
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
    } else if (section == "$Entities") {
      const long long np = size(), nc = size(), ns = size(), nv = size();
      for (long long i = 0; i < np; ++i) {
        i32(); for (int k = 0; k < 3; ++k) f64();
        const std::size_t nphys = c.count(size(), 4);
        for (std::size_t k = 0; k < nphys; ++k) i32();
      }
      for (long long dim = 1; dim <= 3; ++dim) {
        const long long n = dim == 1 ? nc : (dim == 2 ? ns : nv);
        for (long long i = 0; i < n; ++i) {
          const int tag = i32();
          for (int k = 0; k < 6; ++k) f64();
          const std::size_t nphys = c.count(size(), 4);
          for (std::size_t k = 0; k < nphys; ++k) { const int p = i32(); if (dim == 1 && k == 0) b.curve_entity_physical[tag] = p; }
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
        const int physical = dim == 1 && b.curve_entity_physical.count(entity) ? b.curve_entity_physical[entity] : 0;
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
  return std::move(b.mesh);
}

void write_msh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  // One curve entity (and physical curve) per boundary ring and per feature curve, one surface for the quads.
  std::map<int, std::vector<std::size_t>> rings, curves;
  for (std::size_t e = 0; e < mesh.boundary_edges.size(); ++e) rings[mesh.boundary_edge_ring[e]].push_back(e);
  for (std::size_t e = 0; e < mesh.feature_edges.size(); ++e) curves[mesh.feature_edge_curve[e]].push_back(e);
  struct Curve { std::string name; const std::vector<std::array<std::int32_t, 2>>* edges; const std::vector<std::size_t>* ids; };
  std::vector<Curve> entities;
  for (const auto& [r, ids] : rings) entities.push_back({"boundary_ring_" + std::to_string(r), &mesh.boundary_edges, &ids});
  for (const auto& [c, ids] : curves) entities.push_back({"feature_" + std::to_string(c), &mesh.feature_edges, &ids});
  const bool bin = options.binary;
  Box2 box;
  for (Vec2 p : mesh.nodes) box.add(p);

  write_file_atomically(path, [&](std::ostream& os) {
    os.precision(17);
    auto size = [&](std::uint64_t v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 8); else os << v; };
    auto i32 = [&](int v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 4); else os << v; };
    auto f64 = [&](double v) { if (bin) os.write(reinterpret_cast<const char*>(&v), 8); else os << v; };
    auto sep = [&](const char* s) { if (!bin) os << s; };
    os << "$MeshFormat\n4.1 " << (bin ? 1 : 0) << " 8\n";
    if (bin) { i32(1); os << "\n"; }
    os << "$EndMeshFormat\n$PhysicalNames\n" << entities.size() + 1 << "\n2 1 \"domain\"\n";
    for (std::size_t k = 0; k < entities.size(); ++k) os << "1 " << k + 2 << " \"" << entities[k].name << "\"\n";
    os << "$EndPhysicalNames\n$Entities\n";
    size(0); sep(" "); size(entities.size()); sep(" "); size(1); sep(" "); size(0); sep("\n");
    auto bbox = [&] { f64(box.lo.x); sep(" "); f64(box.lo.y); sep(" "); f64(0); sep(" "); f64(box.hi.x); sep(" "); f64(box.hi.y); sep(" "); f64(0); sep(" "); };
    for (std::size_t k = 0; k < entities.size(); ++k) {
      i32(static_cast<int>(k + 1)); sep(" "); bbox(); size(1); sep(" "); i32(static_cast<int>(k + 2)); sep(" "); size(0); sep("\n");
    }
    i32(1); sep(" "); bbox(); size(1); sep(" "); i32(1); sep(" "); size(0); sep("\n");
    if (bin) os << "\n";
    os << "$EndEntities\n$Nodes\n";
    const std::uint64_t nn = mesh.nodes.size();
    size(1); sep(" "); size(nn); sep(" "); size(1); sep(" "); size(nn); sep("\n");
    i32(2); sep(" "); i32(1); sep(" "); i32(0); sep(" "); size(nn); sep("\n");
    for (std::uint64_t v = 1; v <= nn; ++v) { size(v); sep("\n"); }
    for (Vec2 p : mesh.nodes) { f64(p.x); sep(" "); f64(p.y); sep(" "); f64(0); sep("\n"); }
    if (bin) os << "\n";
    os << "$EndNodes\n$Elements\n";
    std::uint64_t nel = mesh.quads.size();
    for (const auto& e : entities) nel += e.ids->size();
    size(entities.size() + 1); sep(" "); size(nel); sep(" "); size(1); sep(" "); size(nel); sep("\n");
    std::uint64_t tag = 1;
    for (std::size_t k = 0; k < entities.size(); ++k) {
      i32(1); sep(" "); i32(static_cast<int>(k + 1)); sep(" "); i32(1); sep(" "); size(entities[k].ids->size()); sep("\n");
      for (std::size_t id : *entities[k].ids) {
        const auto& e = (*entities[k].edges)[id];
        size(tag++); sep(" "); size(static_cast<std::uint64_t>(e[0]) + 1); sep(" "); size(static_cast<std::uint64_t>(e[1]) + 1); sep("\n");
      }
    }
    i32(2); sep(" "); i32(1); sep(" "); i32(3); sep(" "); size(mesh.quads.size()); sep("\n");
    for (const auto& q : mesh.quads) {
      size(tag++);
      for (auto v : q) { sep(" "); size(static_cast<std::uint64_t>(v) + 1); }
      sep("\n");
    }
    if (bin) os << "\n";
    os << "$EndElements\n";
  }, bin);
}

}  // namespace polysquare
