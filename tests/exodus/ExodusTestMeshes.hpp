#pragma once
// Small Exodus II meshes written with the Exodus C API for the tests (tests/exodus/): each with
// volumes, centroids and node sets known in closed form (stated beside each mesh), and the bad
// meshes the reader must refuse. Used by test_exodus_mesh.cpp and make_exodus_meshes.cpp.
#include <exodusII.h>
#include <netcdf.h>

#include <array>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace exotest {

struct Block {
  int id;
  std::string type;          // "HEX8", "TETRA", ...
  int nodesPer;
  std::vector<int> conn;     // 1-based node numbers
  std::string name;
  int attributes;
  std::vector<double> attr;  // attributes per element
  Block(int id_, std::string type_, int nodesPer_, std::vector<int> conn_, std::string name_ = "", int attributes_ = 0,
        std::vector<double> attr_ = {})
      : id(id_), type(std::move(type_)), nodesPer(nodesPer_), conn(std::move(conn_)), name(std::move(name_)),
        attributes(attributes_), attr(std::move(attr_)) {}
};
struct NodeSet {
  int id;
  std::string name;
  std::vector<int> nodes;    // 1-based
};
struct SideSet {
  int id;
  std::string name;
  std::vector<int> elems, sides;  // 1-based
};
struct Mesh {
  int dim = 3;
  std::vector<std::array<double, 3>> nodes;
  std::vector<Block> blocks;
  std::vector<NodeSet> nodeSets;
  std::vector<SideSet> sideSets;
};

inline void check(int rc, const char* what) {
  if (rc < 0) throw std::runtime_error(std::string("exodus test writer: ") + what + " failed");
}

/// Writes m as an Exodus II file: classic netCDF (64-bit offsets, the library's default), or
/// netCDF-4 (HDF5) when `netcdf4`.
inline void write(const std::string& path, const Mesh& m, bool netcdf4 = false) {
  int cpu = sizeof(double), io = sizeof(double);
  const int exo = ex_create(path.c_str(), EX_CLOBBER | (netcdf4 ? EX_NETCDF4 : 0), &cpu, &io);
  check(exo, "ex_create");
  check(ex_set_max_name_length(exo, 80), "ex_set_max_name_length");  // names beyond 32 characters
  int nelem = 0;
  for (const auto& b : m.blocks) nelem += static_cast<int>(b.conn.size()) / b.nodesPer;
  check(ex_put_init(exo, "perinox test mesh", m.dim, static_cast<int>(m.nodes.size()), nelem,
                    static_cast<int>(m.blocks.size()), static_cast<int>(m.nodeSets.size()),
                    static_cast<int>(m.sideSets.size())),
        "ex_put_init");
  std::vector<double> x, y, z;
  for (const auto& n : m.nodes) {
    x.push_back(n[0]);
    y.push_back(n[1]);
    z.push_back(n[2]);
  }
  check(ex_put_coord(exo, x.data(), y.data(), m.dim == 3 ? z.data() : nullptr), "ex_put_coord");
  for (const auto& b : m.blocks) {
    const int count = static_cast<int>(b.conn.size()) / b.nodesPer;
    check(ex_put_elem_block(exo, b.id, b.type.c_str(), count, b.nodesPer, b.attributes), "ex_put_elem_block");
    if (count > 0) check(ex_put_elem_conn(exo, b.id, b.conn.data()), "ex_put_elem_conn");
    if (b.attributes > 0) check(ex_put_elem_attr(exo, b.id, b.attr.data()), "ex_put_elem_attr");
    if (!b.name.empty()) check(ex_put_name(exo, EX_ELEM_BLOCK, b.id, b.name.c_str()), "ex_put_name");
  }
  for (const auto& s : m.nodeSets) {
    check(ex_put_node_set_param(exo, s.id, static_cast<int>(s.nodes.size()), 0), "ex_put_node_set_param");
    check(ex_put_node_set(exo, s.id, s.nodes.data()), "ex_put_node_set");
    if (!s.name.empty()) check(ex_put_name(exo, EX_NODE_SET, s.id, s.name.c_str()), "ex_put_name");
  }
  for (const auto& s : m.sideSets) {
    check(ex_put_side_set_param(exo, s.id, static_cast<int>(s.elems.size()), 0), "ex_put_side_set_param");
    check(ex_put_side_set(exo, s.id, s.elems.data(), s.sides.data()), "ex_put_side_set");
    if (!s.name.empty()) check(ex_put_name(exo, EX_SIDE_SET, s.id, s.name.c_str()), "ex_put_name");
  }
  check(ex_close(exo), "ex_close");
}

/// Replaces the element type name of the position-th element block (1-based) of a written mesh
/// by `type`, of any length, through netCDF: the Exodus writer copies a type name into 33 bytes
/// (a longer one aborts it), so a file with a long one, which the reader must refuse, is made here.
inline void setElementType(const std::string& path, int position, const std::string& type) {
  int nc = -1, var = -1;
  if (nc_open(path.c_str(), NC_WRITE, &nc) != NC_NOERR) throw std::runtime_error("setElementType: cannot open " + path);
  const std::string conn = "connect" + std::to_string(position);
  const bool ok = nc_inq_varid(nc, conn.c_str(), &var) == NC_NOERR && nc_redef(nc) == NC_NOERR &&
                  nc_put_att_text(nc, var, "elem_type", type.size() + 1, type.c_str()) == NC_NOERR && nc_enddef(nc) == NC_NOERR;
  nc_close(nc);
  if (!ok) throw std::runtime_error("setElementType: cannot write the element type of " + path);
}

/// Replaces the title of a written mesh by `title`, of any length, through netCDF (the Exodus
/// writer keeps at most 80 characters).
inline void setTitle(const std::string& path, const std::string& title) {
  int nc = -1;
  if (nc_open(path.c_str(), NC_WRITE, &nc) != NC_NOERR) throw std::runtime_error("setTitle: cannot open " + path);
  const bool ok = nc_redef(nc) == NC_NOERR && nc_put_att_text(nc, NC_GLOBAL, "title", title.size() + 1, title.c_str()) == NC_NOERR &&
                  nc_enddef(nc) == NC_NOERR;
  nc_close(nc);
  if (!ok) throw std::runtime_error("setTitle: cannot write the title of " + path);
}

/// A box of nx x ny x nz hexahedra of edge h from the origin; node (i, j, k) is number
/// 1 + i + (nx+1) (j + (ny+1) k); element (i, j, k) is 1 + i + nx (j + ny k) within the
/// blocks, which split it at x = splitAt elements (block 1 below, block 2 above; splitAt >= nx:
/// one block). Node sets 1 "left" (x = 0) and 2 "right" (x = nx h); side set 1 "right face".
inline Mesh hexBox(int nx, int ny, int nz, double h, int splitAt) {
  Mesh m;
  auto node = [&](int i, int j, int k) { return 1 + i + (nx + 1) * (j + (ny + 1) * k); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.nodes.push_back({i * h, j * h, k * h});
  Block b1{1, "HEX8", 8, {}, "left part"}, b2{2, "HEX8", 8, {}, "right part"};
  std::vector<int> rightElems;
  int e1 = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          if ((i < splitAt) != (pass == 0)) continue;
          Block& b = pass == 0 ? b1 : b2;
          for (int n : {node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                        node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)})
            b.conn.push_back(n);
          ++e1;
          if (i == nx - 1) rightElems.push_back(e1);
        }
  m.blocks.push_back(b1);
  if (!b2.conn.empty()) m.blocks.push_back(b2);
  NodeSet left{1, "left", {}}, right{2, "right", {}};
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j) {
      left.nodes.push_back(node(0, j, k));
      right.nodes.push_back(node(nx, j, k));
    }
  m.nodeSets = {left, right};
  SideSet face{1, "right face", rightElems, std::vector<int>(rightElems.size(), 2)};
  m.sideSets = {face};
  return m;
}

/// One hexahedron, a square frustum: bottom [0,2]^2 at z = 0, top [0.5,1.5]^2 at z = 1.
/// V = h/3 (A1 + A2 + sqrt(A1 A2)) = (4 + 1 + 2)/3 = 7/3; mean of the corners (1, 1, 1/2)
/// (the volume centroid would be at z = 11/28: the particle goes to the corners' mean).
inline Mesh frustum() {
  Mesh m;
  m.nodes = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {0.5, 0.5, 1}, {1.5, 0.5, 1}, {1.5, 1.5, 1}, {0.5, 1.5, 1}};
  m.blocks = {{7, "HEX", 8, {1, 2, 3, 4, 5, 6, 7, 8}}};
  return m;
}

/// The unit cube as six tetrahedra around its diagonal (0,0,0)-(1,1,1) (Kuhn): each volume 1/6,
/// plus one corner tetrahedron (0,0,0), (a,0,0), (0,b,0), (0,0,c) in block 2 with a, b, c =
/// 2, 3, 4 shifted by 10 in x: volume abc/6 = 4, centroid (10 + a/4, b/4, c/4).
inline Mesh tets() {
  Mesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) m.nodes.push_back({double(i), double(j), double(k)});
  // cube node numbers: 1 + i + 2 j + 4 k
  const int o = 1, d = 8;
  const int paths[6][2] = {{2, 4}, {2, 6}, {3, 4}, {3, 7}, {5, 6}, {5, 7}};  // the two middle vertices
  Block b{1, "TETRA", 4, {}};
  for (const auto& p : paths) {
    // vertices o, p0, p1, d in an order with positive volume: (p0-o) x (p1-o) . (d-o) > 0
    auto at = [&](int n) { return m.nodes[n - 1]; };
    const auto a = at(p[0]), c = at(p[1]), e = at(d);
    const double cr[3] = {a[1] * c[2] - a[2] * c[1], a[2] * c[0] - a[0] * c[2], a[0] * c[1] - a[1] * c[0]};
    const bool pos = cr[0] * e[0] + cr[1] * e[1] + cr[2] * e[2] > 0;
    for (int n : {o, pos ? p[0] : p[1], pos ? p[1] : p[0], d}) b.conn.push_back(n);
  }
  m.blocks.push_back(b);
  const int base = static_cast<int>(m.nodes.size());
  m.nodes.push_back({10, 0, 0});
  m.nodes.push_back({12, 0, 0});
  m.nodes.push_back({10, 3, 0});
  m.nodes.push_back({10, 0, 4});
  m.blocks.push_back({2, "TET4", 4, {base + 1, base + 2, base + 3, base + 4}, "corner"});
  m.nodeSets = {{5, "origin", {1}}};  // node (0,0,0): every one of the six cube tetrahedra touches it
  return m;
}

/// A triangular prism: the triangle (0,0), (1,0), (0,1) from z = 0 to 2: volume 1, centroid
/// (1/3, 1/3, 1).
inline Mesh wedge() {
  Mesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
  m.blocks = {{3, "WEDGE6", 6, {1, 2, 3, 4, 5, 6}}};
  return m;
}

/// 2D: a 3 x 2 grid of squares of edge 0.5 (block 1, "QUAD4"), node set 1 "bottom" (y = 0:
/// the three bottom squares), and a trapezoid (block 2, "QUAD") with bottom 2, top 1, height 1
/// at x >= 10: area 1.5, corners' mean (11, 1/2); and a
/// triangle (block 3, "TRI3") (20,0), (22,0), (20,3): area 3, centroid (20 + 2/3, 1).
/// Volumes are area x the scene's thickness.
inline Mesh quads() {
  Mesh m;
  m.dim = 2;
  auto node = [](int i, int j) { return 1 + i + 4 * j; };
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i <= 3; ++i) m.nodes.push_back({0.5 * i, 0.5 * j, 0});
  Block b{1, "QUAD4", 4, {}, "grid"};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i)
      for (int n : {node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)}) b.conn.push_back(n);
  m.blocks.push_back(b);
  const int t = static_cast<int>(m.nodes.size());
  m.nodes.push_back({10, 0, 0});
  m.nodes.push_back({12, 0, 0});
  m.nodes.push_back({11.5, 1, 0});
  m.nodes.push_back({10.5, 1, 0});
  m.blocks.push_back({2, "QUAD", 4, {t + 1, t + 2, t + 3, t + 4}});
  const int r = static_cast<int>(m.nodes.size());
  m.nodes.push_back({20, 0, 0});
  m.nodes.push_back({22, 0, 0});
  m.nodes.push_back({20, 3, 0});
  m.blocks.push_back({3, "TRI3", 3, {r + 1, r + 2, r + 3}});
  m.nodeSets = {{1, "bottom", {node(0, 0), node(1, 0), node(2, 0), node(3, 0)}}};
  return m;
}

/// Sphere elements (particles given directly): attributes radius, volume.
inline Mesh spheres() {
  Mesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  m.blocks = {{4, "SPHERE", 1, {1, 2, 3}, "balls", 2, {0.5, 0.1, 0.5, 0.2, 0.5, 0.3}}};
  m.nodeSets = {{1, "", {3}}, {2, "a node set name longer than thirty-two characters", {1, 2}}};
  return m;
}

// --- meshes the reader must refuse ---
inline Mesh invertedHex() {  // the second unit cube with its top and bottom faces swapped
  Mesh m = hexBox(2, 1, 1, 1.0, 9);
  auto& c = m.blocks[0].conn;
  for (int a = 0; a < 4; ++a) std::swap(c[8 + a], c[8 + 4 + a]);
  return m;
}
inline Mesh flatTet() {  // all four corners in z = 0
  Mesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.blocks = {{1, "TETRA", 4, {1, 2, 3, 4}}};
  return m;
}
inline Mesh pyramid() {
  Mesh m;
  m.nodes = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  m.blocks = {{1, "PYRAMID5", 5, {1, 2, 3, 4, 5}}};
  return m;
}
inline Mesh noBlocks() {
  Mesh m;
  m.nodes = {{0, 0, 0}};
  return m;
}
inline Mesh sphereWithoutVolume() {
  Mesh m;
  m.nodes = {{0, 0, 0}};
  m.blocks = {{1, "SPHERE", 1, {1}, "", 1, {0.5}}};
  return m;
}

}  // namespace exotest
