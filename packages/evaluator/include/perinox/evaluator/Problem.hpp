#pragma once
// A complete, validated problem description, free of Trilinos types: the discretisation
// (replicated on every rank), the material, the effects a scene enables, and the loading.
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

  int dim() const { return disc.dim; }
  bool isFixed(int p, int c) const { return (fixedMask[p] >> c) & 1u; }
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

/// Whether the prescribed DOFs (fixedMask) remove every rigid-body mode (translations and
/// rotations about the body's centre): the modes restricted to the prescribed DOFs have full rank.
bool preventsRigidMotion(const ProblemSpec& problem);

/// Checks a problem built in C++ (or from a scene) for what the evaluator cannot work with: array
/// sizes against the particle count and dimension, finite coordinates, volumes, loads and material
/// constants, a horizon of at least one spacing, consistent effect parameters, and that the
/// prescribed DOFs leave no rigid-body mode free (preventsRigidMotion). Throws
/// std::invalid_argument with one sentence naming the field ("ProblemSpec: ...") otherwise. The
/// evaluator's constructor calls it, so a host program gets the errors a scene gets.
void validateProblem(const ProblemSpec& problem);

}  // namespace perinox
