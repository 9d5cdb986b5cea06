#pragma once
// Particle discretisation: positions, volumes, fictitious (Dirichlet) layers, families.
// Plain C++ and Eigen only. The whole discretisation is built identically on every MPI rank
// (it is deterministic and cheap next to the solve); the evaluator decides ownership.
#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace perinox {

using Vec3 = Eigen::Vector3d;

/// Sides of the lattice's bounding box. Bit i of a side mask is Side(i).
enum class Side : int { XMin = 0, XMax = 1, YMin = 2, YMax = 3, ZMin = 4, ZMax = 5 };
const char* sideName(Side s);                // "xmin", ...
bool parseSide(const std::string& name, Side& out);  // case-insensitive; false if unknown

/// A hole cut out of the real particles of a lattice (fictitious particles are never cut).
struct Hole {
  enum class Kind { Circle, Rectangle } kind = Kind::Circle;
  Vec3 center = Vec3::Zero();
  double radius = 0.0;                  // Circle (2D: disc; 3D: cylinder along z; 1D: interval)
  Vec3 halfWidths = Vec3::Zero();       // Rectangle / box: half extents per axis
};

/// A regular lattice: particles at cell centres of a box split into counts[a] equal cells
/// per axis a < dim. All axes must have the same spacing dx (relative tolerance 1e-9).
struct LatticeSpec {
  int dim = 2;
  Vec3 lower = Vec3::Zero();
  Vec3 upper = Vec3::Ones();
  std::array<int, 3> counts{{1, 1, 1}};
  double thickness = 1.0;               // 2D: out-of-plane thickness h; 1D: cross-section area A
  std::vector<Hole> holes;
  std::vector<Side> fictitiousSides;    // a layer of floor(delta/dx + 1e-9) particle rows outside each
  double horizonFactor = 3.015;         // delta = horizonFactor * dx
  double jitter = 0.0;                  // optional random shift of real particles, fraction of dx
  unsigned jitterSeed = 12345;
};

/// Everything the model needs about particles. Index = global particle id (0..n-1).
struct Discretization {
  int dim = 2;
  double dx = 0.0;                      // nominal spacing (lattice spacing, or given for files)
  double horizon = 0.0;                 // delta
  double thickness = 1.0;
  std::vector<Vec3> X;                  // reference positions (unused components are 0)
  std::vector<double> volume;           // particle volumes V_i (2D: dx^2 h, 1D: dx A, 3D: dx^3)
  std::vector<std::uint8_t> fictitious; // 1 for particles of a fictitious Dirichlet layer
  std::vector<std::uint8_t> sideMask;   // fictitious particles: bit s set when inside the layer of Side(s)
  std::vector<int> block;               // block id (lattice: 1; files: the optional 5th column, else 1)
  // Families in CSR form: neighbours of i are familyIndex[familyOffset[i] .. familyOffset[i+1]).
  // Family of i = all j != i with |X_j - X_i| <= delta * (1 + 1e-12), sorted by j.
  std::vector<std::int64_t> familyOffset;
  std::vector<int> familyIndex;
  Vec3 boxLower = Vec3::Zero(), boxUpper = Vec3::Zero();  // the real body's bounding box

  int size() const { return static_cast<int>(X.size()); }
  int familySize(int i) const { return static_cast<int>(familyOffset[i + 1] - familyOffset[i]); }
};

/// Builds the lattice (real + fictitious particles) and, unless families is false, its families
/// (a scene leaves them to the evaluator, which finds each rank's own: localParticles).
/// Throws std::invalid_argument with a sentence naming the problem (unequal spacing, a
/// horizon below the spacing, no particle left after holes, ...).
Discretization buildLattice(const LatticeSpec& spec, bool families = true);

/// The pieces of buildLattice, for building a lattice in parts (one MPI rank's share): sites are
/// numbered lexicographically (x fastest) over the lattice with its fictitious layers, before
/// holes are cut; the particles keep that order.
std::int64_t latticeSiteCount(const LatticeSpec& spec);
struct LatticeSiteCounts {
  std::int64_t particles = 0, real = 0;  // sites kept (holes cut), and of them real
};
/// The particles of the sites [first, last), counted without building them.
LatticeSiteCounts countLatticeSites(const LatticeSpec& spec, std::int64_t first, std::int64_t last);
/// The particles of the sites [first, last) (no families). realBefore: the real particles of the
/// sites before `first`, so that the jitter continues the whole lattice's random stream.
Discretization latticeSites(const LatticeSpec& spec, std::int64_t first, std::int64_t last, std::int64_t realBefore);

/// A particle file's columns: perinox's "x y z volume [block]", or Peridigm's text-file
/// discretisation, exactly "x y z block volume" (lines starting with '#', '/' or '*' are comments).
enum class ParticleColumns { VolumeThenBlock, BlockThenVolume };

/// Reads a particle file: one particle per line "x y z volume [block]" (or columns as given),
/// '#' starts a comment, blank lines ignored. dim selects how many coordinates matter (the rest
/// must still be present as columns x y z). dx is the nominal spacing (used for reports and
/// horizon factors). Particle i is the file's i-th particle line (0-based, comments and blank
/// lines not counted). Throws std::runtime_error naming the file and line on malformed input.
Discretization readParticleFile(const std::string& path, int dim, double horizon, double dx,
                                double thickness, bool families = true,
                                ParticleColumns columns = ParticleColumns::VolumeThenBlock);

/// The nominal spacing a particle file's volumes imply: the median particle's volume as a
/// length (1D: volume / thickness, the cross-section area), an area's side (2D: volume /
/// thickness) or a cube's edge (3D). Reads (and checks) the whole file.
double particleFileSpacing(const std::string& path, int dim, double thickness,
                           ParticleColumns columns = ParticleColumns::VolumeThenBlock);

/// A particle file read in parts (one MPI rank's share of its bytes, problemOnLocalParticleFile):
/// its size in bytes; the newlines in the bytes [begin, end); and the particles of the lines that
/// start in [begin, end), as readParticleFile reads them (no families; the box is of these
/// particles only). newlinesBefore: the newlines in [0, begin), so that a message names the line
/// as readParticleFile does; lastLine, if given, receives the number of the last line read (0
/// when none starts in the range). Throws std::runtime_error naming the file and line.
std::uint64_t particleFileSize(const std::string& path);
long particleFileNewlines(const std::string& path, std::uint64_t begin, std::uint64_t end);
Discretization readParticleFileRange(const std::string& path, int dim, double horizon, double dx, double thickness,
                                     std::uint64_t begin, std::uint64_t end, long newlinesBefore,
                                     long* lastLine = nullptr,
                                     ParticleColumns columns = ParticleColumns::VolumeThenBlock);

/// (Re)builds the families of d with a cell-list neighbour search, O(n * family size).
void buildFamilies(Discretization& d);

/// Region selection helpers. Each returns sorted particle ids.
enum class Population { Real, Fictitious, All };
std::vector<int> selectBox(const Discretization& d, const Vec3& lo, const Vec3& hi, Population who);
/// Real particles whose distance to side s of the real body's box is below `thickness`
/// (e.g. thickness = dx selects the outermost particle row inside the body).
std::vector<int> selectSideLayer(const Discretization& d, Side s, double thickness);
/// Fictitious particles in the layer of side s.
std::vector<int> selectFictitiousSide(const Discretization& d, Side s);
/// The distance from p to the nearest particle of the population (infinity if none).
double nearestDistance(const Discretization& d, const Vec3& p, Population who);
/// The particle (of the population) nearest to p, -1 if none. Particles as near as the nearest
/// (to 1e-9 of the distance or of the spacing) tie; a tie goes to the smallest x, then y, then z:
/// a rule that depends neither on the particles' order nor on how they are split among ranks.
/// `nearest`: the distance to compare with (a caller that holds part of the body passes the
/// nearest distance over all parts); negative: this discretisation's own nearestDistance.
int selectNearest(const Discretization& d, const Vec3& p, Population who, double nearest = -1);
/// Whether a lies before b in the tie-break order of selectNearest (x, then y, then z).
bool positionBefore(const Vec3& a, const Vec3& b, int dim);

}  // namespace perinox
