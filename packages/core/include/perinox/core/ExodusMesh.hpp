#pragma once
// Exodus II meshes as particle discretisations (docs/exodus.md): one particle per element, at the
// mean of its corner nodes (Peridigm's placement) with the element's exact volume (2D elements: area x thickness); sphere
// elements are particles given directly (volume: their second attribute, as Peridigm reads them).
// Element blocks become block ids; node sets and side sets become particle sets.
// Plain C++; the Exodus II C library (Debian's libexodusii-dev) is used inside the .cpp only.
#include <functional>
#include <string>
#include <vector>

#include "perinox/core/Discretization.hpp"

namespace perinox {

/// One element block of the mesh, in file order.
struct MeshBlock {
  int id = 0;
  std::string name;          // the block's name in the file ("block_<id>" if none, as Peridigm names it)
  std::string elementType;   // as written in the file ("HEX8", "TETRA", "SPHERE", ...)
  int elements = 0;
};

/// A node set or side set turned into particles (sorted ids).
/// Node set: the particles of every element that has at least one node in the set (Peridigm's
/// rule; for sphere elements, the sphere on the node). Side set: the particles of the elements
/// whose sides are listed.
struct MeshSet {
  int id = 0;
  std::string name;          // the set's name in the file (node sets without one: "nodelist_<id>", as
                             // Peridigm names them; side sets: "")
  std::vector<int> particles;
};

struct ExodusMesh {
  Discretization disc;       // families built; block = the element block's id
  std::vector<MeshBlock> blocks;
  std::vector<MeshSet> nodeSets, sideSets;
};

/// True when perinox was built with the Exodus II library.
bool exodusAvailable();

/// Reads an Exodus II mesh. dim is the scene's dimension: 3 takes hex, tet, wedge and sphere
/// elements; 2 takes quad, tri and sphere elements (x and y of the nodes; areas times
/// `thickness`). Higher-order elements (hex20/27, tet10, wedge15/18, quad8/9, tri6/7) are read
/// through their corner nodes. The result has no families yet: disc.dx is the mesh's nominal
/// spacing (the cube root of the median particle volume; 2D: the square root of the median
/// area), disc.horizon 0; set the horizon (and dx if wanted) and call buildFamilies.
/// Throws std::runtime_error with one sentence naming the file (and the block and element) for a
/// missing or non-Exodus file, no element blocks or no elements, an unsupported element type, a
/// degenerate, inverted or zero-volume element, a sphere without its volume attribute; and when
/// perinox was built without Exodus II.
ExodusMesh readExodusMesh(const std::string& path, int dim, double thickness);

/// The particles (0-based element positions in file order, as readExodusMesh numbers them) of
/// elements given by their ids in the mesh's element number map (1, 2, ..., n when the mesh has
/// none): Peridigm's node numbers. -1 for an id the map does not hold. Reads the map in pieces.
std::vector<long long> exodusElementPositions(const std::string& path, int dim, const std::vector<long long>& ids);

/// The sizes a distributed read splits: elements (= particles, over every block) and nodes.
/// Reads the header and the element blocks only; throws as readExodusMesh for a bad file.
struct ExodusMeshSize {
  long long elements = 0, nodes = 0;
};
ExodusMeshSize exodusMeshSize(const std::string& path, int dim);

/// A part of a mesh to read: elements [elementBegin, elementEnd) in file order (block after
/// block; particle ids are these numbers), and the nodes [nodeBegin, nodeEnd) (0-based) whose
/// coordinates this part checks.
struct ExodusRange {
  long long elementBegin = 0, elementEnd = 0, nodeBegin = 0, nodeEnd = 0;
};
/// Runs one phase of a read. A distributed read passes one that agrees on failures across the
/// ranks (each rank reads its own part, and all must stop at the same phase); a whole read runs
/// the phase as it is.
using ReadPhase = std::function<void(const std::function<void()>&)>;

/// The part `range` of the mesh, as readExodusMesh reads the whole (which is this with every
/// element and node): disc holds the range's elements in order (box and spacing of those alone;
/// the caller of a part takes the body's), blocks every element block, and each node or side set
/// its members in the range (global element numbers). The coordinates and set lists are read in
/// pieces of at most 65 536 entries, so no list of the whole mesh's size is held. Three phases:
/// header, blocks and the range's node coordinates; the range's elements; the sets.
ExodusMesh readExodusMeshRange(const std::string& path, int dim, double thickness, const ExodusRange& range,
                               const ReadPhase& phase);

/// A mesh's nominal spacing from its median particle volume (3D: the cube root; 2D: the square
/// root of volume / thickness).
double meshSpacing(const Discretization& d, double medianVolume);

}  // namespace perinox
