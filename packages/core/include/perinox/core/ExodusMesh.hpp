#pragma once
// Exodus II meshes as particle discretisations (docs/exodus.md): one particle per element, at the
// mean of its corner nodes (Peridigm's placement) with the element's exact volume (2D elements: area x thickness); sphere
// elements are particles given directly (volume: their second attribute, as Peridigm reads them).
// Element blocks become block ids; node sets and side sets become particle sets.
// Plain C++; the Exodus II C library (Debian's libexodusii-dev) is used inside the .cpp only.
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

}  // namespace perinox
