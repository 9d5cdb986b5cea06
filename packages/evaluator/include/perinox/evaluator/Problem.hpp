#pragma once
// A complete, validated problem description, free of Trilinos types: the discretisation (the
// whole body on every rank, or, distributed, each rank's share of it), the material, the effects
// a scene enables, and the loading.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "perinox/core/Discretization.hpp"
#include "perinox/material/Material.hpp"
#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"

namespace Teuchos {
template <class T> class RCP;
template <class O> class Comm;
}  // namespace Teuchos

namespace perinox {

/// A rigid rotation superposed on the loading: at load factor lambda the body is turned by
/// lambda * angle about the axis through the centre. Prescribed particles go to
/// R (X + lambda u_bar - c) + c and dead loads turn with the body (lambda R f_bar), so a scene's
/// solution with the rotation is R times the one without (objectivity through the solver).
/// The prescribed motion is nonlinear in lambda: it follows the arc, not the chord.
struct RotationSpec {
  double angle = 0.0;                   // radians at load factor 1; 0 = off
  Vec3 axis = Vec3(0, 0, 1);            // unit vector (2D: z)
  Vec3 center = Vec3::Zero();
};

/// A block's own material and effects (ProblemSpec::blocks): the particles with disc.block[p] == id.
struct BlockSpec {
  int id = 1;
  MaterialSpec material;                // the block's material (same dim as the problem)
  std::optional<double> G;              // stabilisation G; unset: the problem's stab.G
  double C = StabilizationSpec::kFromMaterial;  // micromodulus; default: micromodulusC of this block's material
  std::optional<DamageSpec> damage;     // damage law; unset: the problem's damageSpec
};

struct ProblemSpec {
  Discretization disc;
  MaterialSpec material;
  bool correspondence = true;
  bool stabilization = false;
  StabilizationSpec stab;               // C left at its default: computed (stabilizationSpec())
  bool damage = false;
  DamageSpec damageSpec;
  bool stressPoints = false;            // replaces the plain correspondence force state
  unsigned stressPointSeed = 2018;
  bool control = false;
  ControlSpec controlSpec;
  std::vector<double> modulusScale;     // per particle E_i / E; empty for a uniform material
  // Blocks with their own materials: empty = every particle has `material` (and stab, damageSpec).
  // Otherwise every particle's disc.block must have an entry; particle i's element uses its
  // block's material, G and C, and a bond the damage law of the end with the smaller critical
  // stretch (docs/exodus.md, "Blocks with their own materials").
  std::vector<BlockSpec> blocks;
  // Loading at load factor 1 (scaled by the load factor lambda):
  std::vector<std::uint8_t> fixedMask;  // per particle: bit c set when component c is prescribed
  std::vector<double> prescribed;       // per particle * dim: prescribed displacement at lambda = 1
  std::vector<double> bodyForce;        // per particle * dim: body force density at lambda = 1
  RotationSpec rotation;                // superposed rigid rotation (angle 0: none, costs nothing)
  PartitionMethod partition = PartitionMethod::Rcb;  // which particles each MPI rank owns

  // Distributed form (issue 17; problemOnLocalLattice builds it). false: disc and the
  // per-particle arrays above (modulusScale, fixedMask, prescribed, bodyForce, disc.block) cover
  // the whole body, the same on every rank, and a particle's index is its global id. true: they
  // cover this rank's share only: the particles it owns (`owned`, sorted global ids, already
  // partitioned: `partition` is not consulted) and every particle within two horizons of them;
  // disc's particle i is global particle globalId[i] (ascending), globalCount particles in all.
  // No array of the whole body's size exists on any rank. The evaluator speaks global ids
  // (ownedParticles, freeDof, reactionOn, ...); region selections on the share's disc give
  // indices into it, which globalId turns into global ids.
  bool distributed = false;
  std::vector<long long> globalId;
  std::vector<long long> owned;
  long long globalCount = 0;

  int dim() const { return disc.dim; }
  /// Particles of the whole body.
  long long particleCount() const { return distributed ? globalCount : disc.size(); }
  /// Whether disc holds global particle g (any g of the body unless distributed).
  bool holds(long long g) const;
  /// Whether this rank owns global particle g (every particle unless distributed): what a count
  /// over the ranks adds up.
  bool owns(long long g) const;
  /// Index into disc (and the per-particle arrays) of global particle g: g itself unless
  /// distributed. Throws std::out_of_range when this rank's share does not hold g.
  int index(long long g) const;
  /// The global ids of particles given by their indices into disc (a region selected on a
  /// distributed problem's share, for the evaluator's reactionOn or meanDisplacement).
  std::vector<int> globalIds(const std::vector<int>& indices) const;
  /// Whether component c of global particle g is prescribed.
  bool isFixed(long long g, int c) const { return (fixedMask[index(g)] >> c) & 1u; }
  bool rotates() const { return rotation.angle != 0.0; }
  /// The stabilisation's parameters as the model gets them: stab, with C = micromodulusC(material,
  /// disc.horizon, disc.thickness) when it was left at StabilizationSpec::kFromMaterial (a host
  /// sets only G, as a scene does).
  StabilizationSpec stabilizationSpec() const;
  /// The same for a block: its G (or stab.G) and its C (or micromodulusC of its material).
  StabilizationSpec stabilizationSpec(const BlockSpec& b) const;
  /// Per particle, the index of its block in `blocks` (empty when blocks is empty). Throws
  /// std::invalid_argument (one sentence) when a particle's block has no entry.
  std::vector<int> blockIndex() const;
  /// The materials in force: {material}, or the blocks' materials in their order.
  std::vector<MaterialSpec> materials() const;
  /// Whether a material in force is plastic (the model then keeps a state per particle, and the
  /// outputs carry the equivalent plastic strain and the yield flag).
  bool plastic() const;
  /// The largest Young's modulus in force (for round-off floors and frozen-DOF stiffnesses).
  double stiffestModulus() const;
  /// A non-zero displacement is prescribed somewhere (otherwise the load is dead loads only).
  bool prescribesDisplacement() const {
    for (double v : prescribed)
      if (v != 0.0) return true;
    return false;
  }
};

/// A problem on a lattice (buildLattice) of the given material, its loading arrays sized: nothing
/// prescribed, no body force, correspondence only. Hosts then prescribe and enable effects.
std::shared_ptr<ProblemSpec> problemOnLattice(const LatticeSpec& lattice, const MaterialSpec& material);

/// Prescribes component c of the given particles at load factor 1: u_c(X) = value(X).
void prescribe(ProblemSpec& problem, const std::vector<int>& particles, int component,
               const std::function<double(const Vec3& X)>& value);
/// The same with one value for all of them (0: a support).
void prescribe(ProblemSpec& problem, const std::vector<int>& particles, int component, double value = 0.0);

/// A distributed problem on this rank's share of a lattice (collective over comm): the particles
/// are generated in slabs and partitioned by `partition` (the same owners as ownedParticles gives
/// the whole lattice), and each rank keeps its owned particles and those within two horizons of
/// them; no rank builds an array of the whole lattice's size. Loading arrays sized, nothing
/// prescribed, as problemOnLattice. The selection helpers (selectBox, selectSideLayer, ...) work
/// on the share's disc (the real body's box is the whole lattice's), so prescribe() applies a
/// geometric condition rank by rank. Defined in Partitioner.cpp (Zoltan2).
std::shared_ptr<ProblemSpec> problemOnLocalLattice(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                   const LatticeSpec& lattice, const MaterialSpec& material,
                                                   PartitionMethod partition = PartitionMethod::Rcb);

/// A particle file to read distributed: its path and what readParticleFile takes with it.
struct ParticleFileSpec {
  std::string path;
  int dim = 2;
  double horizon = 0.0, dx = 0.0, thickness = 1.0;
  ParticleColumns columns = ParticleColumns::VolumeThenBlock;
};

/// The same on this rank's share of a particle file (collective): each rank reads the lines that
/// start in its slice of the file's bytes (particle ids in the file's order, as readParticleFile
/// numbers them), the particles are partitioned by `partition` (the owners ownedParticles gives
/// the whole file), and each rank keeps its owned particles and those within two horizons of
/// them. A malformed file is refused on every rank with readParticleFile's message (the first bad
/// line's) as std::runtime_error. Defined in Partitioner.cpp.
std::shared_ptr<ProblemSpec> problemOnLocalParticleFile(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                        const ParticleFileSpec& file, const MaterialSpec& material,
                                                        PartitionMethod partition = PartitionMethod::Rcb);

/// The same on particles each rank brings (collective): `slab` holds this rank's particles (X,
/// volume, and block, fictitious and side flags if given) with the consecutive ids firstId,
/// firstId + 1, ..., where firstId is the particle count of the lower ranks (a rank may bring
/// none); its dim, thickness, dx and horizon are the body's (the box is taken over the ranks).
/// For a host program with its own distributed reader, and for meshes read in parts. A slab
/// whose firstId does not follow the lower ranks', no particles on any rank, a horizon that is
/// not positive or sizes that disagree are refused as std::invalid_argument on every rank.
std::shared_ptr<ProblemSpec> problemOnLocalParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                     const Discretization& slab, long long firstId,
                                                     const MaterialSpec& material,
                                                     PartitionMethod partition = PartitionMethod::Rcb);

/// The number of rigid-body modes in dim dimensions (1, 3 or 6), and component a of mode m at a
/// point r from the modes' centre: modes 0..dim-1 the translations, then in 2D the in-plane
/// rotation (-r_y, r_x), in 3D the rotations e_k x r about axis k = m - 3. The one definition the
/// rigid-body check, the Krylov near-null space and the auxiliary operators' modes use.
inline int rigidModeCount(int dim) { return dim == 1 ? 1 : (dim == 2 ? 3 : 6); }
inline double rigidModeValue(int m, int a, int dim, const Vec3& r) {
  if (m < dim) return m == a ? 1.0 : 0.0;
  if (dim == 2) return a == 0 ? -r[1] : r[0];
  Vec3 w = Vec3::Zero();
  w[m - 3] = 1.0;
  return w.cross(r)[a];
}

/// The Gram matrix of the rigid-body modes (translations and rotations about the body's box
/// centre, lengths in units of dx) restricted to the prescribed DOFs of the particles counted:
/// all of disc, or the owned ones when distributed (sum it over the ranks).
Eigen::MatrixXd rigidModeGram(const ProblemSpec& problem);
/// Whether a (summed) Gram matrix has full rank.
bool gramHasFullRank(const Eigen::MatrixXd& M);
/// Whether the prescribed DOFs (fixedMask) remove every rigid-body mode (translations and
/// rotations about the body's centre): the modes restricted to the prescribed DOFs have full rank.
/// For a distributed problem use the collective form below.
bool preventsRigidMotion(const ProblemSpec& problem);
/// The same over the ranks of comm (collective): a distributed problem's rigidModeGram summed over
/// the ranks; a replicated one's on its own. Defined in PeridynamicEvaluator.cpp.
bool preventsRigidMotion(const Teuchos::Comm<int>& comm, const ProblemSpec& problem);
/// The prescribed displacement components (fixedMask bits) of the whole body, counted over the
/// ranks' owned particles (collective). Defined in PeridynamicEvaluator.cpp.
long long prescribedDofCount(const Teuchos::Comm<int>& comm, const ProblemSpec& problem);

/// Checks a problem built in C++ (or from a scene) for what the evaluator cannot work with: array
/// sizes against the particle count and dimension, finite coordinates, volumes, loads and material
/// constants, a horizon of at least one spacing, consistent effect parameters, and that the
/// prescribed DOFs leave no rigid-body mode free (preventsRigidMotion; for a distributed problem,
/// which it checks for its share's consistency, the evaluator checks this collectively). Throws
/// std::invalid_argument with one sentence naming the field ("ProblemSpec: ...") otherwise. The
/// evaluator's constructor calls it, so a host program gets the errors a scene gets.
void validateProblem(const ProblemSpec& problem);

}  // namespace perinox
