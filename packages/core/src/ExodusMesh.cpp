// Exodus II meshes as particles (docs/exodus.md). The geometry (centroids and exact volumes of
// linear elements) is plain C++; the file is read through the Exodus II C API (6.02's classic
// calls: ex_get_init, ex_get_elem_block, ex_get_elem_conn, ...), only when perinox was built
// with it (PERINOX_HAVE_EXODUS).
#include "perinox/core/ExodusMesh.hpp"
#include "perinox/core/InputFile.hpp"
#include "NetcdfHeader.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

#ifdef PERINOX_HAVE_EXODUS
#include <exodusII.h>
#include <netcdf.h>
#endif

namespace perinox {

bool exodusAvailable() {
#ifdef PERINOX_HAVE_EXODUS
  return true;
#else
  return false;
#endif
}

double meshSpacing(const Discretization& d, double medianVolume) {
  return d.dim == 3 ? std::cbrt(medianVolume) : std::sqrt(medianVolume / d.thickness);
}

#ifdef PERINOX_HAVE_EXODUS

namespace {

enum class Shape { Hex, Tet, Wedge, Quad, Tri, Sphere, Unsupported };

/// Element family from the file's type name (case-insensitive) and its node count. Higher-order
/// elements keep their corners first (Exodus ordering), so they are read through those.
Shape shapeOf(const std::string& type, int nodes, int& corners) {
  std::string t;
  for (char c : type) t += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  auto starts = [&](const char* p) { return t.rfind(p, 0) == 0; };
  auto allowed = [&](std::initializer_list<int> counts) {
    return std::find(counts.begin(), counts.end(), nodes) != counts.end();
  };
  if (starts("HEX") && allowed({8, 20, 27})) return corners = 8, Shape::Hex;
  if (starts("TET") && allowed({4, 8, 10, 11, 14, 15})) return corners = 4, Shape::Tet;
  if (starts("WEDGE") && allowed({6, 15, 16, 18, 20, 21})) return corners = 6, Shape::Wedge;
  if (starts("QUAD") && allowed({4, 5, 8, 9})) return corners = 4, Shape::Quad;
  if (starts("TRI") && !starts("TRISHELL") && allowed({3, 4, 6, 7})) return corners = 3, Shape::Tri;
  if (starts("SPHERE") && nodes == 1) return corners = 1, Shape::Sphere;
  return Shape::Unsupported;
}

bool threeD(Shape s) { return s == Shape::Hex || s == Shape::Tet || s == Shape::Wedge; }

/// Position and volume of one element from its corner nodes. The position is the mean of the
/// corners (as Peridigm places its particles, and as shared/benchmarks/tensile_bar_points.txt
/// has them; it is the centroid for tets, triangles and parallelepipeds, and differs from the
/// volume centroid of a general hex, wedge or quad); the volume is exact for the element's
/// (tri)linear shape. ok = false when the Jacobian
/// determinant is not positive somewhere it is sampled (3D: at every corner and quadrature
/// point; 2D: of one sign at every corner and point, as either node order is a valid
/// orientation of a planar element) or the volume is not positive.
struct Measure {
  Vec3 centroid = Vec3::Zero();
  double volume = 0.0;
  bool ok = true;
};

// Gauss-Legendre, 2 points on [-1, 1]: exact for a trilinear map's Jacobian determinant
// (degree <= 2 per variable), so the volume is exact.
const double kGauss[2] = {-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)};

Measure hexMeasure(const std::array<Vec3, 8>& x) {
  // Exodus/Patran hex: nodes 0-3 the bottom face counter-clockwise, 4-7 the top one.
  static const double s[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                 {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  Measure m;
  auto at = [&](double r, double t, double u) {  // det J of the trilinear map at (r, t, u)
    Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 8; ++a) {
      const double fr = 1 + s[a][0] * r, ft = 1 + s[a][1] * t, fu = 1 + s[a][2] * u;
      J.col(0) += s[a][0] * ft * fu / 8 * x[a];
      J.col(1) += fr * s[a][1] * fu / 8 * x[a];
      J.col(2) += fr * ft * s[a][2] / 8 * x[a];
    }
    return J.determinant();
  };
  for (int a = 0; a < 8; ++a)
    if (!(at(s[a][0], s[a][1], s[a][2]) > 0)) m.ok = false;
  for (double r : kGauss)
    for (double t : kGauss)
      for (double u : kGauss) {
        const double det = at(r, t, u);
        if (!(det > 0)) m.ok = false;
        m.volume += det;  // weights 1
      }
  for (const Vec3& p : x) m.centroid += p / 8;
  m.ok = m.ok && m.volume > 0;
  return m;
}

Measure tetMeasure(const std::array<Vec3, 4>& x) {
  Measure m;
  m.volume = (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]) / 6;
  m.centroid = (x[0] + x[1] + x[2] + x[3]) / 4;
  m.ok = m.volume > 0;
  return m;
}

Measure wedgeMeasure(const std::array<Vec3, 6>& x) {
  // Nodes 0-2 the bottom triangle, 3-5 the top one above them. Map: triangle coordinates (r, t)
  // times a linear coordinate u in [-1, 1]. The Jacobian determinant has degree 1 in (r, t) and 2
  // in u: the 3-point degree-2 triangle rule by 2-point Gauss integrates it exactly.
  Measure m;
  auto at = [&](double r, double t, double u) {  // det J at (r, t, u)
    const double L[3] = {1 - r - t, r, t};
    const double dr[3] = {-1, 1, 0}, dt[3] = {-1, 0, 1};
    Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
    for (int a = 0; a < 3; ++a)
      for (int lvl = 0; lvl < 2; ++lvl) {
        const double f = lvl == 0 ? (1 - u) / 2 : (1 + u) / 2, df = lvl == 0 ? -0.5 : 0.5;
        const Vec3& p = x[a + 3 * lvl];
        J.col(0) += dr[a] * f * p;
        J.col(1) += dt[a] * f * p;
        J.col(2) += L[a] * df * p;
      }
    return J.determinant();
  };
  static const double corner[6][3] = {{0, 0, -1}, {1, 0, -1}, {0, 1, -1}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  for (const auto& c : corner)
    if (!(at(c[0], c[1], c[2]) > 0)) m.ok = false;
  static const double tri[3][2] = {{1.0 / 6, 1.0 / 6}, {2.0 / 3, 1.0 / 6}, {1.0 / 6, 2.0 / 3}};
  for (const auto& q : tri)
    for (double u : kGauss) {
      const double w = 1.0 / 6;  // triangle weight (area 1/2 over 3 points) times the Gauss weight 1
      const double det = at(q[0], q[1], u);
      if (!(det > 0)) m.ok = false;
      m.volume += w * det;
    }
  for (const Vec3& p : x) m.centroid += p / 6;
  m.ok = m.ok && m.volume > 0;
  return m;
}

/// 2D: area in the x-y plane (either orientation), times nothing: the caller multiplies by the
/// thickness.
Measure quadMeasure(const std::array<Vec3, 4>& x) {
  static const double s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  Measure m;
  auto at = [&](double r, double t) {  // det J of the bilinear map at (r, t)
    Eigen::Matrix2d J = Eigen::Matrix2d::Zero();
    for (int a = 0; a < 4; ++a) {
      const double fr = 1 + s[a][0] * r, ft = 1 + s[a][1] * t;
      J.col(0) += s[a][0] * ft / 4 * x[a].head<2>();
      J.col(1) += fr * s[a][1] / 4 * x[a].head<2>();
    }
    return J.determinant();
  };
  int positive = 0, negative = 0;
  for (const auto& c : s) {
    const double det = at(c[0], c[1]);
    positive += det > 0;
    negative += det < 0;
  }
  double signedArea = 0;
  for (double r : kGauss)
    for (double t : kGauss) {
      const double det = at(r, t);
      positive += det > 0;
      negative += det < 0;
      signedArea += det;
    }
  m.ok = (positive == 8 || negative == 8) && signedArea != 0;
  for (const Vec3& p : x) m.centroid += p / 4;
  m.volume = std::abs(signedArea);
  return m;
}

Measure triMeasure(const std::array<Vec3, 3>& x) {
  Measure m;
  const Eigen::Vector2d a = (x[1] - x[0]).head<2>(), b = (x[2] - x[0]).head<2>();
  m.volume = std::abs(a[0] * b[1] - a[1] * b[0]) / 2;
  m.centroid = (x[0] + x[1] + x[2]) / 3;
  m.ok = m.volume > 0;
  return m;
}

}  // namespace

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw std::runtime_error(path + ": " + what); }

/// An open Exodus file, closed on every way out.
struct ExodusFile {
  int id = -1;
  ~ExodusFile() {
    if (id >= 0) ex_close(id);
  }
};

std::string entityName(int exo, ex_entity_type type, int id) {
  char buf[MAX_STR_LENGTH + 1 + 256] = {0};  // names longer than 32 characters are cut by the library
  if (ex_get_name(exo, type, id, buf) < 0) return "";
  std::string s(buf);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  return s;
}

std::string blockLabel(int id, const std::string& name) {
  const bool given = !name.empty() && name != "block_" + std::to_string(id);
  return "element block " + std::to_string(id) + (given ? " ('" + printable(name) + "')" : "");
}

}  // namespace

namespace {

/// Refuses a file that is not netCDF (classic/64-bit offset "CDF\001", "CDF\002", "CDF\005", or
/// netCDF-4 on HDF5 "\211HDF") before the Exodus library sees it.
void checkNetcdf(const std::string& path) {
  requireRegularFile(path, "Exodus mesh");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) fail(path, "cannot open the Exodus mesh for reading (no such file, or not readable)");
  char magic[4] = {0, 0, 0, 0};
  probe.read(magic, 4);
  const bool cdf = magic[0] == 'C' && magic[1] == 'D' && magic[2] == 'F';
  const bool hdf = magic[1] == 'H' && magic[2] == 'D' && magic[3] == 'F';
  if (!cdf && !hdf) fail(path, "is not an Exodus II file (not a netCDF file)");
  if (cdf) {
    try {
      checkClassicNetcdfHeader(path);
    } catch (const std::runtime_error& e) {
      fail(path, std::string(e.what()) + " (a damaged Exodus II file)");
    }
  }
  // netCDF-4 (HDF5) files are read too. One that netCDF cannot open is refused here: the Exodus
  // library would print three lines of its own, blaming a netCDF without netCDF-4 support.
  int nc = -1;
  if (hdf && nc_open(path.c_str(), NC_NOWRITE, &nc) != NC_NOERR)
    fail(path, "is an HDF5 file that netCDF cannot read (a damaged netCDF-4 Exodus II file, or not one)");
  if (nc >= 0) nc_close(nc);
}

/// The mesh's header.
struct MeshHeader {
  int numDim = 0, numNodes = 0, numElem = 0, numBlocks = 0, numNodeSets = 0, numSideSets = 0;
};

MeshHeader readHeader(int exo, const std::string& path, int dim) {
  MeshHeader h;
  char title[MAX_LINE_LENGTH + 1] = {0};
  if (ex_get_init(exo, title, &h.numDim, &h.numNodes, &h.numElem, &h.numBlocks, &h.numNodeSets, &h.numSideSets) < 0)
    fail(path, "is not an Exodus II file (no Exodus header)");
  if (h.numBlocks <= 0) fail(path, "has no element blocks");
  if (h.numElem <= 0) fail(path, "has no elements");
  if (h.numElem > kMaxParticles || h.numNodes > 8 * kMaxParticles || h.numBlocks > kMaxParticles ||
      h.numNodeSets > kMaxParticles || h.numSideSets > kMaxParticles)
    fail(path, "declares " + std::to_string(h.numElem) + " elements, " + std::to_string(h.numNodes) + " nodes and " +
                   std::to_string(h.numBlocks) + " blocks: more than perinox reads (at most " + std::to_string(kMaxParticles) +
                   " elements, one particle each)");
  if (h.numDim < 2 || h.numDim > 3) fail(path, "has " + std::to_string(h.numDim) + "-dimensional coordinates (2 or 3 are read)");
  if (dim == 3 && h.numDim < 3) fail(path, "is a 2D mesh but the scene is 3D ('Discretization/Dimension' = 3)");
  return h;
}

/// Entries read per library call when a list (coordinates, a set) is read in pieces: a rank holds
/// at most this many of a list it does not keep.
constexpr long long kChunk = 1 << 16;

/// Calls f(node, x) for the nodes [first, first + count) (0-based), read in pieces; x has the
/// file's z (0 for 2D meshes).
template <class F>
void forNodes(int exo, const std::string& path, const MeshHeader& h, long long first, long long count, F&& f) {
  std::vector<double> x, y, z;
  for (long long a = first; a < first + count; a += kChunk) {
    const long long m = std::min(kChunk, first + count - a);
    x.assign(m, 0.0), y.assign(m, 0.0), z.assign(m, 0.0);
    if (ex_get_partial_coord(exo, a + 1, m, x.data(), y.data(), h.numDim == 3 ? z.data() : nullptr) < 0)
      fail(path, "has unreadable node coordinates");
    for (long long k = 0; k < m; ++k) f(a + k, Vec3(x[k], y[k], z[k]));
  }
}

/// One block's element type and size, checked against the scene's dimension.
struct BlockLayout {
  Shape shape = Shape::Unsupported;
  int count = 0, nodesPer = 0, attrs = 0, corners = 0;
};

/// The element type name of the position-th element block (1-based), read through netCDF into a
/// buffer of the attribute's own length: the Exodus library copies the whole attribute into the
/// caller's MAX_STR_LENGTH + 1 characters, however long the file says it is.
std::string elementTypeName(int exo, const std::string& path, int position, const MeshBlock& blk) {
  int var = -1;
  nc_type kind = NC_NAT;
  std::size_t length = 0;
  const std::string conn = "connect" + std::to_string(position);
  if (nc_inq_varid(exo, conn.c_str(), &var) != NC_NOERR || nc_inq_att(exo, var, "elem_type", &kind, &length) != NC_NOERR ||
      kind != NC_CHAR)
    fail(path, "has an unreadable " + blockLabel(blk.id, blk.name) + " (no element type)");
  if (length > MAX_STR_LENGTH + 1)
    fail(path, blockLabel(blk.id, blk.name) + " has an element type name of " + std::to_string(length) +
                   " bytes, longer than Exodus' " + std::to_string(MAX_STR_LENGTH) + " characters");
  std::string type(length, '\0');
  if (length > 0 && nc_get_att_text(exo, var, "elem_type", type.data()) != NC_NOERR)
    fail(path, "has an unreadable " + blockLabel(blk.id, blk.name) + " (no element type)");
  type.resize(std::strlen(type.c_str()));  // up to the first NUL
  return type;
}

BlockLayout readBlockLayout(int exo, const std::string& path, int dim, int position, MeshBlock& blk) {
  BlockLayout L;
  blk.elementType = elementTypeName(exo, path, position, blk);
  // Only now may the library copy the type name: it fits MAX_STR_LENGTH + 1 characters.
  char type[MAX_STR_LENGTH + 1] = {0};
  if (ex_get_elem_block(exo, blk.id, type, &L.count, &L.nodesPer, &L.attrs) < 0)
    fail(path, "has an unreadable " + blockLabel(blk.id, blk.name));
  blk.elements = L.count;
  if (L.count == 0) return L;
  const std::string where = blockLabel(blk.id, blk.name);
  L.shape = shapeOf(blk.elementType, L.nodesPer, L.corners);
  if (L.shape == Shape::Unsupported)
    fail(path, where + " has elements of type '" + printable(blk.elementType) + "' with " + std::to_string(L.nodesPer) +
                   " nodes, which perinox does not read (hex, tet, wedge and sphere in 3D; quad, tri and sphere in 2D)");
  if (dim == 3 && (L.shape == Shape::Quad || L.shape == Shape::Tri))
    fail(path, where + " has 2D elements ('" + printable(blk.elementType) + "') but the scene is 3D ('Discretization/Dimension' = 3)");
  if (dim == 2 && threeD(L.shape))
    fail(path, where + " has 3D elements ('" + printable(blk.elementType) + "') but the scene is 2D ('Discretization/Dimension' = 2)");
  if (L.shape == Shape::Sphere && L.attrs < 2)  // Peridigm's rule: attribute 1 the radius, 2 the volume
    fail(path, where + " has sphere elements with " + std::to_string(L.attrs) +
                   " attribute(s); the volume is read from the second attribute (radius, volume)");
  return L;
}

/// An open mesh: its header and its element blocks (names, types, sizes), checked.
struct OpenMesh {
  ExodusFile file;
  MeshHeader h;
  std::vector<MeshBlock> blocks;
  std::vector<BlockLayout> layouts;
  long long elements = 0;  // over the blocks: the particles
};

void openMesh(const std::string& path, int dim, OpenMesh& m) {
  if (dim != 2 && dim != 3) fail(path, "Exodus meshes are for 2D and 3D scenes ('Discretization/Dimension' = 2 or 3)");
  checkNetcdf(path);
  ex_opts(0);  // no messages on stderr and no abort: every failure becomes this reader's sentence
  int cpuWordSize = sizeof(double), ioWordSize = 0;
  float version = 0;
  m.file.id = ex_open(path.c_str(), EX_READ, &cpuWordSize, &ioWordSize, &version);
  if (m.file.id < 0) fail(path, "is not an Exodus II file (the Exodus library cannot open it)");
  const int exo = m.file.id;
  // Names longer than Exodus' default 32 characters come back whole only when asked for.
  const int usedNameLength = static_cast<int>(ex_inquire_int(exo, EX_INQ_DB_MAX_USED_NAME_LENGTH));
  if (usedNameLength > MAX_STR_LENGTH) ex_set_max_name_length(exo, std::min(usedNameLength, 256));
  m.h = readHeader(exo, path, dim);
  std::vector<int> blockIds(m.h.numBlocks);
  if (ex_get_elem_blk_ids(exo, blockIds.data()) < 0) fail(path, "has unreadable element block ids");
  for (int id : blockIds) {
    MeshBlock blk;
    blk.id = id;
    blk.name = entityName(exo, EX_ELEM_BLOCK, id);
    if (blk.name.empty()) blk.name = "block_" + std::to_string(id);  // Peridigm's name for an unnamed block
    for (const MeshBlock& other : m.blocks)
      if (other.id == id) fail(path, "has two element blocks with id " + std::to_string(id));
    if (id < 0) fail(path, "has element block id " + std::to_string(id) + " (block ids must be 0 or more, as 'Blocks' names them)");
    m.layouts.push_back(readBlockLayout(exo, path, dim, static_cast<int>(m.blocks.size()) + 1, blk));
    m.elements += m.layouts.back().count;
    m.blocks.push_back(blk);
  }
  if (m.elements == 0) fail(path, "has no elements in its element blocks");
  if (m.elements != m.h.numElem)
    fail(path, "has " + std::to_string(m.elements) + " elements in its element blocks but declares " + std::to_string(m.h.numElem) +
                   " (a damaged Exodus II file)");
}

/// Centroid and volume of one element from its corners (sphere: the node and the volume
/// attribute); one sentence naming the element when it is degenerate, inverted or of no volume.
Measure elementMeasure(const std::string& path, const std::string& element, const std::string& type, Shape shape,
                       const std::array<Vec3, 8>& x, double sphereVolume) {
  Measure m;
  switch (shape) {
    case Shape::Hex: m = hexMeasure(x); break;
    case Shape::Tet: m = tetMeasure({x[0], x[1], x[2], x[3]}); break;
    case Shape::Wedge: m = wedgeMeasure({x[0], x[1], x[2], x[3], x[4], x[5]}); break;
    case Shape::Quad: m = quadMeasure({x[0], x[1], x[2], x[3]}); break;
    case Shape::Tri: m = triMeasure({x[0], x[1], x[2]}); break;
    default:  // sphere
      m.centroid = x[0];
      m.volume = sphereVolume;
      if (!(m.volume > 0) || !std::isfinite(m.volume))
        fail(path, element + " is a sphere with volume " + messageNumber(m.volume) + " (its second attribute must be positive)");
      m.ok = true;
  }
  if (m.ok && m.volume < kSmallestVolume)
    fail(path, element + " ('" + type + "') has volume " + messageNumber(m.volume) + ", below " + messageNumber(kSmallestVolume) +
                   " (products of two volumes would underflow)");
  if (!m.ok) {
    if (m.volume == 0) fail(path, element + " ('" + type + "') has zero volume (degenerate: coincident or flat corners)");
    fail(path, element + " ('" + type + "') is inverted or degenerate (its Jacobian determinant is not positive everywhere: " +
                   "check the node order)");
  }
  return m;
}

/// Sorted, without repeats.
void uniqueSorted(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// One block's elements in the range: their connectivity (and sphere attributes).
struct BlockSlice {
  std::size_t block = 0;   // index in OpenMesh::blocks
  long long first = 0;     // global number (0-based) of the slice's first element
  long long blockFirst = 0;  // ... and of the block's first element
  int count = 0;
  std::vector<int> conn;
  std::vector<double> attr;
};

/// Reads the elements [begin, end) (file order, block after block) into particles, appended to
/// mesh.disc in that order; for every node they touch, the pairs (node, local particle) sorted
/// (for the node sets). The coordinates of the nodes they name are read in pieces.
void readElements(const OpenMesh& m, const std::string& path, double thickness, long long begin, long long end,
                  ExodusMesh& mesh, std::vector<std::pair<int, int>>& elementsOfNode) {
  const int exo = m.file.id;
  Discretization& d = mesh.disc;
  std::vector<BlockSlice> slices;
  long long start = 0;
  for (std::size_t b = 0; b < m.blocks.size(); start += m.layouts[b].count, ++b) {
    const BlockLayout& L = m.layouts[b];
    const long long lo = std::max(start, begin), hi = std::min(start + L.count, end);
    if (lo >= hi) continue;
    BlockSlice s;
    s.block = b, s.first = lo, s.blockFirst = start, s.count = static_cast<int>(hi - lo);
    const std::string where = blockLabel(m.blocks[b].id, m.blocks[b].name);
    s.conn.resize(static_cast<std::size_t>(s.count) * L.nodesPer);
    if (ex_get_partial_conn(exo, EX_ELEM_BLOCK, m.blocks[b].id, lo - start + 1, s.count, s.conn.data(), nullptr, nullptr) < 0)
      fail(path, "has unreadable connectivity in " + where);
    if (L.shape == Shape::Sphere) {
      s.attr.resize(static_cast<std::size_t>(s.count) * L.attrs);
      if (ex_get_partial_attr(exo, EX_ELEM_BLOCK, m.blocks[b].id, lo - start + 1, s.count, s.attr.data()) < 0)
        fail(path, "has unreadable sphere attributes in " + where);
    }
    slices.push_back(std::move(s));
  }
  // The corners' coordinates: the nodes named, read in pieces of at most kChunk consecutive
  // numbers around them.
  std::vector<int> needed;
  for (const BlockSlice& s : slices)
    for (int node : s.conn)
      if (node >= 1 && node <= m.h.numNodes) needed.push_back(node);
  uniqueSorted(needed);
  std::vector<Vec3> coords(needed.size());
  for (std::size_t i = 0; i < needed.size();) {
    const long long a = needed[i] - 1;
    std::size_t j = i;
    while (j < needed.size() && needed[j] - 1 < a + kChunk) ++j;
    std::size_t k = i;
    forNodes(exo, path, m.h, a, needed[j - 1] - a, [&](long long node, const Vec3& x) {
      if (node + 1 == needed[k]) coords[k++] = x;
    });
    i = j;
  }
  for (const BlockSlice& s : slices) {
    const BlockLayout& L = m.layouts[s.block];
    const MeshBlock& blk = m.blocks[s.block];
    const std::string where = blockLabel(blk.id, blk.name);
    for (int e = 0; e < s.count; ++e) {
      const long long elem = s.first + e;
      const std::string element = "element " + std::to_string(elem + 1) + " of " + where;
      std::array<Vec3, 8> x;
      for (int a = 0; a < L.nodesPer; ++a) {
        const int node = s.conn[static_cast<std::size_t>(e) * L.nodesPer + a];
        if (node < 1 || node > m.h.numNodes)
          fail(path, element + " names node " + std::to_string(node) + ", but the mesh has " + std::to_string(m.h.numNodes) + " nodes");
        if (a < L.corners) x[a] = coords[std::lower_bound(needed.begin(), needed.end(), node) - needed.begin()];
        elementsOfNode.emplace_back(node, static_cast<int>(d.X.size()));
      }
      const double sphereVolume = L.shape == Shape::Sphere ? s.attr[static_cast<std::size_t>(e) * L.attrs + 1] : 0.0;
      Measure me = elementMeasure(path, element, printable(blk.elementType), L.shape, x, sphereVolume);
      if (L.shape == Shape::Quad || L.shape == Shape::Tri) me.volume *= thickness;
      if (d.dim == 2) me.centroid[2] = 0;  // 2D: the x-y plane (as particle files do)
      d.X.push_back(me.centroid);
      d.volume.push_back(me.volume);
      d.block.push_back(blk.id);
    }
  }
  std::sort(elementsOfNode.begin(), elementsOfNode.end());
  elementsOfNode.erase(std::unique(elementsOfNode.begin(), elementsOfNode.end()), elementsOfNode.end());
}

/// Node sets: the particles of the elements touching the set's nodes (Peridigm's rule), those of
/// the range (global numbers, sorted). Every set is read whole, in pieces.
void readNodeSets(int exo, const std::string& path, const MeshHeader& h, long long begin,
                  const std::vector<std::pair<int, int>>& elementsOfNode, ExodusMesh& mesh) {
  if (h.numNodeSets <= 0) return;
  std::vector<int> ids(h.numNodeSets);
  if (ex_get_node_set_ids(exo, ids.data()) < 0) fail(path, "has unreadable node set ids");
  std::vector<int> nodes;
  for (int id : ids) {
    MeshSet set;
    set.id = id;
    set.name = entityName(exo, EX_NODE_SET, id);
    if (set.name.empty()) set.name = "nodelist_" + std::to_string(id);  // Peridigm's name for an unnamed node set
    int n = 0, df = 0;
    if (ex_get_node_set_param(exo, id, &n, &df) < 0) fail(path, "has an unreadable node set " + std::to_string(id));
    for (long long a = 0; a < n; a += kChunk) {
      const long long m = std::min<long long>(kChunk, n - a);
      nodes.assign(m, 0);
      if (ex_get_partial_node_set(exo, id, a + 1, m, nodes.data()) < 0) fail(path, "has an unreadable node set " + std::to_string(id));
      for (int node : nodes) {
        if (node < 1 || node > h.numNodes)
          fail(path, "node set " + std::to_string(id) + " names node " + std::to_string(node) + ", but the mesh has " +
                         std::to_string(h.numNodes) + " nodes");
        for (auto it = std::lower_bound(elementsOfNode.begin(), elementsOfNode.end(), std::make_pair(node, -1));
             it != elementsOfNode.end() && it->first == node; ++it)
          set.particles.push_back(static_cast<int>(begin + it->second));
      }
    }
    uniqueSorted(set.particles);
    mesh.nodeSets.push_back(set);
  }
}

/// Side sets: the particles of the listed elements (Peridigm ignores side sets), those of the
/// range [begin, end) of the mesh's `elements`.
void readSideSets(int exo, const std::string& path, const MeshHeader& h, long long elements, long long begin,
                  long long end, ExodusMesh& mesh) {
  if (h.numSideSets <= 0) return;
  std::vector<int> ids(h.numSideSets);
  if (ex_get_side_set_ids(exo, ids.data()) < 0) fail(path, "has unreadable side set ids");
  std::vector<int> elems, sides;
  for (int id : ids) {
    MeshSet set;
    set.id = id;
    set.name = entityName(exo, EX_SIDE_SET, id);
    int n = 0, df = 0;
    if (ex_get_side_set_param(exo, id, &n, &df) < 0) fail(path, "has an unreadable side set " + std::to_string(id));
    for (long long a = 0; a < n; a += kChunk) {
      const long long m = std::min<long long>(kChunk, n - a);
      elems.assign(m, 0), sides.assign(m, 0);
      if (ex_get_partial_side_set(exo, id, a + 1, m, elems.data(), sides.data()) < 0)
        fail(path, "has an unreadable side set " + std::to_string(id));
      for (int e : elems) {
        if (e < 1 || e > elements)
          fail(path, "side set " + std::to_string(id) + " names element " + std::to_string(e) + ", but the mesh has " +
                         std::to_string(elements) + " elements");
        if (e - 1 >= begin && e - 1 < end) set.particles.push_back(e - 1);
      }
    }
    uniqueSorted(set.particles);
    mesh.sideSets.push_back(set);
  }
}

/// The discretisation's box, flags and nominal spacing from its particles: the median
/// particle's edge (3D: volume^(1/3); 2D: (volume / h)^(1/2)). The horizon is the scene's (0
/// here). No particles: box and spacing stay 0 (a range's caller takes the body's).
void finishDiscretization(Discretization& d) {
  const std::size_t n = d.X.size();
  d.fictitious.assign(n, 0);
  d.sideMask.assign(n, 0);
  d.horizon = 0;
  if (n == 0) return;
  d.boxLower = d.X[0];
  d.boxUpper = d.X[0];
  for (const Vec3& x : d.X) {
    d.boxLower = d.boxLower.cwiseMin(x);
    d.boxUpper = d.boxUpper.cwiseMax(x);
  }
  std::vector<double> v(d.volume);
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  d.dx = meshSpacing(d, v[v.size() / 2]);
}

}  // namespace

ExodusMeshSize exodusMeshSize(const std::string& path, int dim) {
  OpenMesh m;
  openMesh(path, dim, m);
  return {m.elements, m.h.numNodes};
}

ExodusMesh readExodusMeshRange(const std::string& path, int dim, double thickness, const ExodusRange& range,
                               const ReadPhase& phase) {
  if (!(thickness > 0) || !std::isfinite(thickness)) fail(path, "the thickness must be positive and finite");
  OpenMesh m;
  ExodusMesh mesh;
  mesh.disc.dim = dim;
  mesh.disc.thickness = thickness;
  std::vector<std::pair<int, int>> elementsOfNode;  // (node, local particle), sorted
  // 1. Header and blocks; every coordinate of the range's nodes finite.
  phase([&] {
    openMesh(path, dim, m);
    forNodes(m.file.id, path, m.h, range.nodeBegin, range.nodeEnd - range.nodeBegin, [&](long long node, const Vec3& x) {
      if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
        fail(path, "node " + std::to_string(node + 1) + " has a coordinate that is not a finite number");
    });
    mesh.blocks = m.blocks;
  });
  // 2. The range's elements; 3. the sets.
  phase([&] { readElements(m, path, thickness, range.elementBegin, range.elementEnd, mesh, elementsOfNode); });
  phase([&] {
    readNodeSets(m.file.id, path, m.h, range.elementBegin, elementsOfNode, mesh);
    readSideSets(m.file.id, path, m.h, m.elements, range.elementBegin, range.elementEnd, mesh);
  });
  finishDiscretization(mesh.disc);
  return mesh;
}

std::vector<long long> exodusElementPositions(const std::string& path, int dim, const std::vector<long long>& ids) {
  OpenMesh m;
  openMesh(path, dim, m);
  std::vector<long long> wanted(ids);
  std::sort(wanted.begin(), wanted.end());
  wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
  std::vector<long long> positionOf(wanted.size(), -1);
  std::vector<int> map;
  for (long long a = 0; a < m.elements; a += kChunk) {
    const long long n = std::min(kChunk, m.elements - a);
    map.assign(static_cast<std::size_t>(n), 0);
    // A mesh without a map reads as 1, 2, ..., n (the library's default).
    if (ex_get_partial_id_map(m.file.id, EX_ELEM_MAP, a + 1, n, map.data()) < 0) fail(path, "has an unreadable element number map");
    for (long long k = 0; k < n; ++k) {
      const auto at = std::lower_bound(wanted.begin(), wanted.end(), static_cast<long long>(map[k]));
      if (at != wanted.end() && *at == map[k]) {
        long long& pos = positionOf[static_cast<std::size_t>(at - wanted.begin())];
        if (pos >= 0) fail(path, "numbers two elements " + std::to_string(map[k]) + " in its element number map");
        pos = a + k;
      }
    }
  }
  std::vector<long long> out;
  out.reserve(ids.size());
  for (long long id : ids) out.push_back(positionOf[static_cast<std::size_t>(std::lower_bound(wanted.begin(), wanted.end(), id) - wanted.begin())]);
  return out;
}

ExodusMesh readExodusMesh(const std::string& path, int dim, double thickness) {
  const ExodusMeshSize size = exodusMeshSize(path, dim);
  return readExodusMeshRange(path, dim, thickness, {0, size.elements, 0, size.nodes},
                             [](const std::function<void()>& f) { f(); });
}

#else

namespace {
[[noreturn]] void withoutExodus(const std::string& path) {
  throw std::runtime_error(path + ": this perinox was built without Exodus II, so it cannot read Exodus meshes "
                                  "(install libexodusii-dev, e.g. with scripts/setup.sh, and rebuild)");
}
}  // namespace

ExodusMeshSize exodusMeshSize(const std::string& path, int) { withoutExodus(path); }
ExodusMesh readExodusMeshRange(const std::string& path, int, double, const ExodusRange&, const ReadPhase&) { withoutExodus(path); }
ExodusMesh readExodusMesh(const std::string& path, int, double) { withoutExodus(path); }
std::vector<long long> exodusElementPositions(const std::string& path, int, const std::vector<long long>&) { withoutExodus(path); }

#endif

}  // namespace perinox
