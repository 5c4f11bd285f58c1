// VTK XML unstructured grid (write; read ASCII), the SVG picture, and the extension dispatch.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include <oneapi/tbb/parallel_for.h>

#include "crs_info.h"
#include "polysquare/core/error.h"
#include "polysquare/io/atomic_file.h"
#include "polysquare/io/mesh_io.h"
#include "polysquare/io/solver_files.h"
#include "polysquare/io/svg.h"
#include "polysquare/quality/quality.h"

namespace polysquare {

std::string lower_extension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

namespace {

// Text content of the first DataArray at or after `from` (plain search: std::regex recurses per character and
// overflows the stack on large files).
std::string array_text(const std::string& xml, std::size_t from, const std::string& what, const std::string& path) {
  const std::size_t open = from == std::string::npos ? from : xml.find("<DataArray", from);
  const std::size_t start = open == std::string::npos ? open : xml.find('>', open);
  const std::size_t end = start == std::string::npos ? start : xml.find("</DataArray>", start);
  if (end == std::string::npos) throw InputError(path + ": no ASCII DataArray for " + what);
  if (xml.compare(open, start - open, "<DataArray") == 0 && xml.find("format=\"ascii\"", open) > start)
    throw InputError(path + ": only ASCII DataArrays are supported (" + what + ")");
  return xml.substr(start + 1, end - start - 1);
}
std::string data_array(const std::string& xml, const std::string& name, const std::string& path) {
  const std::size_t at = xml.find("Name=\"" + name + "\"");
  return array_text(xml, at == std::string::npos ? at : xml.rfind("<DataArray", at), name, path);
}

template <typename T>
std::vector<T> numbers(const std::string& text, const std::string& path) {
  std::istringstream is(text);
  std::vector<T> out;
  T v;
  while (is >> v) out.push_back(v);
  if (!is.eof()) throw InputError(path + ": malformed number in a DataArray");
  return out;
}

// Text for an XML comment: no "--" inside and no '-' at its end.
std::string comment_text(const std::string& text) {
  std::string out;
  for (char ch : text) {
    if (ch == '-' && !out.empty() && out.back() == '-') out += ' ';
    out += ch == '\n' || ch == '\r' ? ' ' : ch;
  }
  if (!out.empty() && out.back() == '-') out += ' ';
  return out;
}

}  // namespace

QuadMesh read_vtu(const std::filesystem::path& path) { return parse_vtu(read_file(path), path.string()); }

QuadMesh parse_vtu(const std::string& xml, const std::string& name) {
  if (xml.find("<UnstructuredGrid") == std::string::npos) throw InputError(name + ": not a VTK UnstructuredGrid file");
  const auto xyz = numbers<double>(array_text(xml, xml.find("<Points>"), "Points", name), name);
  const auto conn = numbers<long long>(data_array(xml, "connectivity", name), name);
  const auto offs = numbers<long long>(data_array(xml, "offsets", name), name);
  const auto types = numbers<int>(data_array(xml, "types", name), name);
  if (xyz.size() % 3 != 0 || offs.size() != types.size()) throw InputError(name + ": inconsistent array sizes");
  QuadMesh mesh;
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) mesh.nodes.push_back({xyz[i], xyz[i + 1]});
  long long start = 0;
  auto node = [&](long long k) {
    if (k < 0 || static_cast<std::size_t>(k) >= conn.size() || conn[k] < 0 || static_cast<std::size_t>(conn[k]) >= mesh.nodes.size())
      throw InputError(name + ": connectivity out of range");
    return static_cast<std::int32_t>(conn[k]);
  };
  for (std::size_t c = 0; c < types.size(); ++c) {
    const long long end = offs[c];
    if (end < start) throw InputError(name + ": decreasing offsets");
    if (types[c] == 9 && end - start == 4) mesh.quads.push_back({node(start), node(start + 1), node(start + 2), node(start + 3)});
    else if (types[c] == 5 && end - start == 3) mesh.triangles.push_back({node(start), node(start + 1), node(start + 2)});
    else if (types[c] != 1 && types[c] != 3 && types[c] != 4)  // vertices and lines carry no area
      throw InputError(name + ": cell " + std::to_string(c) + " has VTK type " + std::to_string(types[c]) + " with " +
                       std::to_string(end - start) + " nodes; only triangles (5) and quadrilaterals (9) are read" +
                       (types[c] >= 10 && types[c] <= 14 ? " (it is a 3D cell)" : ""));
    start = end;
  }
  // The CRS our writer records as field data (a VTK file from another tool has none).
  const std::size_t epsg_at = xml.find("Name=\"crs_epsg\"");
  if (epsg_at != std::string::npos && epsg_at < xml.find("<Piece")) {
    const auto epsg = numbers<long long>(array_text(xml, xml.rfind("<DataArray", epsg_at), "crs_epsg", name), name);
    if (epsg.size() == 1 && epsg[0] > 0 && epsg[0] < 1000000) mesh.crs = "EPSG:" + std::to_string(epsg[0]);
  }
  return mesh;
}

namespace {

// The XML of one VTU file (a whole mesh, or one piece of a .pvtu).
void vtu_text(std::ostream& os, const QuadMesh& mesh) {
  const QuadMetrics q = quad_metrics(mesh);
  os.precision(17);
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
     << "<UnstructuredGrid>\n";
  // The CRS as field data readers keep (VTK, ParaView, meshio's field_data): its EPSG code, 0 when none is
  // identified. The CRS itself (any PROJ string or WKT) goes into a comment at the end: a String array would be
  // VTK's way, but meshio 5 refuses String arrays.
  const crs::CrsInfo info = crs::crs_info(mesh.crs);
  if (!mesh.crs.empty())
    os << "<FieldData>\n<DataArray type=\"Int32\" Name=\"crs_epsg\" NumberOfTuples=\"1\" format=\"ascii\">\n"
       << info.epsg << "\n</DataArray>\n</FieldData>\n";
  os << "<Piece NumberOfPoints=\"" << mesh.nodes.size() << "\" NumberOfCells=\"" << mesh.quads.size() << "\">\n"
     << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (Vec2 p : mesh.nodes) os << p.x << " " << p.y << " 0\n";
  os << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& c : mesh.quads) os << c[0] << " " << c[1] << " " << c[2] << " " << c[3] << "\n";
  os << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t i = 1; i <= mesh.quads.size(); ++i) os << 4 * i << "\n";
  os << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < mesh.quads.size(); ++i) os << "9\n";
  os << "</DataArray>\n</Cells>\n<CellData Scalars=\"scaled_jacobian\">\n";
  auto field = [&](const char* name, const std::vector<double>& v) {
    os << "<DataArray type=\"Float64\" Name=\"" << name << "\" format=\"ascii\">\n";
    for (double x : v) os << x << "\n";
    os << "</DataArray>\n";
  };
  field("scaled_jacobian", q.sj);
  field("eta", q.eta);
  field("skewness", q.skew);
  field("edge_ratio", q.edge_ratio);
  os << "<DataArray type=\"Int32\" Name=\"part\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < mesh.quads.size(); ++i) os << (mesh.quad_part.empty() ? 0 : mesh.quad_part[i]) << "\n";
  os << "</DataArray>\n</CellData>\n<PointData>\n<DataArray type=\"UInt8\" Name=\"node_kind\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < mesh.nodes.size(); ++i)
    os << (mesh.node_kind.empty() ? 0 : static_cast<int>(mesh.node_kind[i])) << "\n";
  os << "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n";
  if (!mesh.crs.empty()) {
    os << "<!-- crs: " << comment_text(mesh.crs) << " -->\n";
    if (info.known) os << "<!-- crs_name: " << comment_text(info.name) << " -->\n<!-- crs_wkt: " << comment_text(info.wkt) << " -->\n";
  }
  os << "</VTKFile>\n";
}

// The quads in the order of their subregion (quad_part): a .pvtu's pieces are runs of it of nearly equal length,
// so each piece is a few neighbouring subregions.
std::vector<std::size_t> piece_order(const QuadMesh& mesh) {
  std::vector<std::size_t> order(mesh.quads.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (mesh.quad_part.size() == mesh.quads.size())
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mesh.quad_part[a] < mesh.quad_part[b]; });
  return order;
}

// Piece k of `pieces`: its run of `order`, with the nodes its quads use.
QuadMesh piece_of(const QuadMesh& mesh, const std::vector<std::size_t>& order, std::size_t k, std::size_t pieces) {
  QuadMesh piece;
  piece.crs = mesh.crs;
  piece.units = mesh.units;
  std::unordered_map<std::int32_t, std::int32_t> local;
  for (std::size_t i = k * order.size() / pieces; i < (k + 1) * order.size() / pieces; ++i) {
    const std::size_t q = order[i];
    std::array<std::int32_t, 4> quad{};
    for (std::size_t c = 0; c < 4; ++c) {
      const std::int32_t v = mesh.quads[q][c];
      auto [it, added] = local.try_emplace(v, static_cast<std::int32_t>(piece.nodes.size()));
      if (added) {
        piece.nodes.push_back(mesh.nodes[static_cast<std::size_t>(v)]);
        if (!mesh.node_kind.empty()) piece.node_kind.push_back(mesh.node_kind[static_cast<std::size_t>(v)]);
      }
      quad[c] = it->second;
    }
    piece.quads.push_back(quad);
    if (!mesh.quad_part.empty()) piece.quad_part.push_back(mesh.quad_part[q]);
  }
  return piece;
}

}  // namespace

std::filesystem::path pvtu_piece_path(const std::filesystem::path& pvtu, std::size_t k) {
  return pvtu.parent_path() / (pvtu.stem().string() + "_" + std::to_string(k) + ".vtu");
}

void write_vtu(const std::filesystem::path& path, const QuadMesh& mesh) {
  write_file_atomically(path, [&](std::ostream& os) { vtu_text(os, mesh); }, false);
}

std::size_t pvtu_pieces(const QuadMesh& mesh, std::size_t pieces) {
  if (pieces == 0) pieces = (mesh.quads.size() + kQuadsPerPiece - 1) / kQuadsPerPiece;
  return std::clamp<std::size_t>(pieces, 1, std::max<std::size_t>(1, mesh.quads.size()));
}

void write_pvtu(const std::filesystem::path& path, const QuadMesh& mesh, std::size_t pieces, std::size_t piece_rank,
                std::size_t piece_processes) {
  pieces = pvtu_pieces(mesh, pieces);
  for (std::size_t k = piece_rank; k < pieces; k += piece_processes) check_output_file(pvtu_piece_path(path, k), "a piece of " + path.string(), {".vtu"});
  const std::vector<std::size_t> order = piece_order(mesh);
  // This process's pieces are built and written in parallel, each to its own temporary, one at a time per thread
  // (not all held at once); all are committed with the .pvtu (atomic_file.h).
  oneapi::tbb::parallel_for(std::size_t{0}, pieces, [&](std::size_t k) {
    if (k % piece_processes == piece_rank) write_vtu(pvtu_piece_path(path, k), piece_of(mesh, order, k, pieces));
  });
  if (piece_rank != 0) return;
  write_file_atomically(path, [&](std::ostream& os) {
    os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
       << "<PUnstructuredGrid GhostLevel=\"0\">\n";
    if (!mesh.crs.empty()) os << "<PFieldData>\n<PDataArray type=\"Int32\" Name=\"crs_epsg\"/>\n</PFieldData>\n";
    os << "<PPoints>\n<PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n</PPoints>\n"
       << "<PCells>\n<PDataArray type=\"Int64\" Name=\"connectivity\"/>\n<PDataArray type=\"Int64\" Name=\"offsets\"/>\n"
       << "<PDataArray type=\"UInt8\" Name=\"types\"/>\n</PCells>\n<PCellData Scalars=\"scaled_jacobian\">\n";
    for (const char* name : {"scaled_jacobian", "eta", "skewness", "edge_ratio"})
      os << "<PDataArray type=\"Float64\" Name=\"" << name << "\"/>\n";
    os << "<PDataArray type=\"Int32\" Name=\"part\"/>\n</PCellData>\n"
       << "<PPointData>\n<PDataArray type=\"UInt8\" Name=\"node_kind\"/>\n</PPointData>\n";
    for (std::size_t k = 0; k < pieces; ++k) os << "<Piece Source=\"" << pvtu_piece_path(path, k).filename().string() << "\"/>\n";
    os << "</PUnstructuredGrid>\n";
    if (!mesh.crs.empty()) os << "<!-- crs: " << comment_text(mesh.crs) << " -->\n";
    os << "</VTKFile>\n";
  }, false);
}

QuadMesh read_pvtu(const std::filesystem::path& path) {
  const std::string xml = read_file(path);
  if (xml.find("<PUnstructuredGrid") == std::string::npos)
    throw InputError(path.string() + ": not a VTK PUnstructuredGrid file");
  // The pieces, their nodes merged where they coincide (a piece's nodes on its seams are the same coordinates,
  // written with 17 digits, in its neighbours).
  QuadMesh mesh;
  std::unordered_map<std::uint64_t, std::vector<std::int32_t>> at;  // hash of a position -> nodes there
  auto key = [](Vec2 p) {
    std::uint64_t a = 0, b = 0;
    std::memcpy(&a, &p.x, sizeof a);
    std::memcpy(&b, &p.y, sizeof b);
    return a * 0x9E3779B97F4A7C15ull ^ b;
  };
  std::size_t pieces = 0;
  for (std::size_t from = xml.find("<Piece"); from != std::string::npos; from = xml.find("<Piece", from + 1)) {
    const std::size_t src = xml.find("Source=\"", from), end = xml.find('>', from);
    if (src == std::string::npos || src > end) throw InputError(path.string() + ": a Piece without a Source");
    const std::size_t close = xml.find('"', src + 8);
    if (close == std::string::npos || close > end) throw InputError(path.string() + ": a Piece with an unterminated Source");
    const std::filesystem::path source = path.parent_path() / xml.substr(src + 8, close - src - 8);
    const QuadMesh piece = read_vtu(source);
    std::vector<std::int32_t> index(piece.nodes.size());
    for (std::size_t v = 0; v < piece.nodes.size(); ++v) {
      const Vec2 p = piece.nodes[v];
      auto& there = at[key(p)];
      std::int32_t found = -1;
      for (std::int32_t u : there)
        if (mesh.nodes[static_cast<std::size_t>(u)].x == p.x && mesh.nodes[static_cast<std::size_t>(u)].y == p.y) found = u;
      if (found < 0) {
        found = static_cast<std::int32_t>(mesh.nodes.size());
        mesh.nodes.push_back(p);
        there.push_back(found);
      }
      index[v] = found;
    }
    for (const auto& q : piece.quads) mesh.quads.push_back({index[q[0]], index[q[1]], index[q[2]], index[q[3]]});
    for (const auto& t : piece.triangles) mesh.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
    if (mesh.crs.empty()) mesh.crs = piece.crs;
    ++pieces;
  }
  if (pieces == 0) throw InputError(path.string() + ": no Piece");
  return mesh;
}


QuadMesh read_mesh(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  QuadMesh mesh;
  if (ext == ".msh") mesh = read_msh(path);
  else if (ext == ".vtu") mesh = read_vtu(path);
  else if (ext == ".pvtu") mesh = read_pvtu(path);
  else throw InputError(path.string() + ": unsupported mesh format '" + ext + "' (supported: .msh, .vtu, .pvtu)");
  // Orientation by majority of signed cell areas: individual inverted cells stay inverted.
  double area = 0.0;
  for (const auto& q : mesh.quads)
    area += cross(mesh.nodes[q[2]] - mesh.nodes[q[0]], mesh.nodes[q[3]] - mesh.nodes[q[1]]) > 0 ? 1.0 : -1.0;
  for (const auto& t : mesh.triangles) area += orient2(mesh.nodes[t[0]], mesh.nodes[t[1]], mesh.nodes[t[2]]) > 0 ? 1.0 : -1.0;
  if (area < 0) {
    for (auto& q : mesh.quads) std::reverse(q.begin(), q.end());
    for (auto& t : mesh.triangles) std::reverse(t.begin(), t.end());
  }
  return mesh;
}

void write_mesh(const std::filesystem::path& path, const QuadMesh& mesh, const MeshWriteOptions& options) {
  const std::string ext = lower_extension(path);
  if (ext == ".msh") return write_msh(path, mesh, options);
  if (ext == ".vtu") return write_vtu(path, mesh);
  if (ext == ".pvtu") return write_pvtu(path, mesh, options.pieces, options.piece_rank, std::max<std::size_t>(1, options.piece_processes));
  if (ext == ".gr3") return write_gr3(path, mesh, options);
  if (ext == ".nc") return write_ugrid(path, mesh, options);
  if (ext == ".2dm") return write_2dm(path, mesh, options);
  if (ext == ".exo") return write_exodus(path, mesh, options);
  throw InputError(path.string() + ": unsupported output format '" + ext + "' (supported: .msh, .vtu, .pvtu, .gr3, .nc, .2dm, .exo)");
}

void write_svg(const std::filesystem::path& path, const QuadMesh& mesh, const Region* region, const SvgOptions& options) {
  Box2 box;
  for (Vec2 p : mesh.nodes) box.add(p);
  if (region) for (const Ring& r : region->rings) for (Vec2 p : r.points) box.add(p);
  const double w = box.hi.x - box.lo.x, h = box.hi.y - box.lo.y;
  const double scale = (options.width_px - 20) / std::max(w, 1e-300);
  const int height = static_cast<int>(h * scale) + 60;
  auto X = [&](Vec2 p) { return 10 + (p.x - box.lo.x) * scale; };
  auto Y = [&](Vec2 p) { return 10 + (box.hi.y - p.y) * scale; };  // y axis up
  const QuadMetrics q = quad_metrics(mesh);
  const double sj_min = q.sj.empty() ? 0.0 : *std::min_element(q.sj.begin(), q.sj.end());
  write_file_atomically(path, [&](std::ostream& os) {
    os.precision(6);
    os << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << options.width_px << "\" height=\"" << height << "\">\n"
       << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    for (std::size_t k = 0; k < mesh.quads.size(); ++k) {
      // Red (SJ <= 0.3, below the acceptable range) to green (SJ = 1).
      const double t = std::clamp((q.sj[k] - 0.3) / 0.7, 0.0, 1.0);
      os << "<polygon points=\"";
      for (auto v : mesh.quads[k]) os << X(mesh.nodes[v]) << "," << Y(mesh.nodes[v]) << " ";
      os << "\" fill=\"rgb(" << static_cast<int>(230 * (1 - t) + 120 * t) << "," << static_cast<int>(80 + 140 * t) << ",90)\" "
         << "stroke=\"black\" stroke-width=\"0.3\"/>\n";
    }
    auto lines = [&](const std::vector<std::array<std::int32_t, 2>>& edges, const char* colour, double width) {
      for (const auto& e : edges)
        os << "<line x1=\"" << X(mesh.nodes[e[0]]) << "\" y1=\"" << Y(mesh.nodes[e[0]]) << "\" x2=\"" << X(mesh.nodes[e[1]])
           << "\" y2=\"" << Y(mesh.nodes[e[1]]) << "\" stroke=\"" << colour << "\" stroke-width=\"" << width << "\"/>\n";
    };
    lines(mesh.boundary_edges, "black", 1.5);
    lines(mesh.feature_edges, "blue", 1.5);
    // Named boundary segments over the boundary: open ones magenta, others orange.
    if (region)
      for (const BoundarySegment& b : region->boundary_segments) {
        os << "<polyline fill=\"none\" stroke=\"" << (b.kind == "open" ? "magenta" : "orange") << "\" stroke-width=\"3\" points=\"";
        for (Vec2 p : b.line) os << X(p) << "," << Y(p) << " ";
        std::string title;
        for (char ch : b.name) title += ch == '<' ? "&lt;" : ch == '>' ? "&gt;" : ch == '&' ? "&amp;" : std::string(1, ch);
        os << "\"><title>" << title << "</title></polyline>\n";
      }
    os << "<text x=\"10\" y=\"" << height - 15 << "\" font-family=\"sans-serif\" font-size=\"14\">" << mesh.quads.size()
       << " quads, scaled Jacobian min " << sj_min << " (red &lt;= 0.3, green = 1)</text>\n</svg>\n";
  }, false);
}

}  // namespace polysquare
