#pragma once
// perinox's auxiliary operators for the two-stage preconditioner (TwoStagePreconditioner.hpp):
// local elasticity operators on the particles of a PeridynamicEvaluator.
//  - Lattice FEM: the bilinear (2D) / trilinear (3D) / linear (1D) finite-element stiffness of the
//    lattice through all particles (cells whose corners are all particles), with the scene's E,
//    nu, planar mode, thickness and per-particle modulus scale; independent of the state, so its
//    hierarchy is built once per run. Needs the particles on a lattice of spacing dx.
//  - Short Horizon: the Jacobian of the same body (material, effects, fixed DOFs) with the
//    families rebuilt at a horizon of a few spacings, at the unloaded state; rebuilt, with the
//    body's broken bonds removed and its detached particles frozen, when bonds break.
#include "perinox/solver/TwoStagePreconditioner.hpp"

#include "perinox/material/Material.hpp"

#include <Eigen/Dense>
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>

#include <memory>

namespace perinox {

class PeridynamicEvaluator;
struct Discretization;

/// Element stiffness of a segment / square / cube of side h (isotropic linear elasticity, E and nu
/// of m, its planar mode; 2D: times the thickness, 1D: thickness = the cross-section area; 2x2(x2)
/// Gauss points), nodes in lexicographic order of their (i, j, k) offsets, DOFs interleaved.
Eigen::MatrixXd latticeElementStiffness(int dim, double h, const MaterialSpec& m, double thickness);

/// Whether every particle of d sits on the lattice of spacing d.dx through the lowest particle
/// (to 1e-6 dx), one particle per site.
bool onLattice(const Discretization& d);

/// The source the two-stage list ("Preconditioner Types/Two-Stage") asks for: its "Auxiliary
/// Operator" and "Auxiliary Horizon Factor". Auto is Lattice FEM on a lattice without damage, Short
/// Horizon otherwise. Throws std::invalid_argument with a sentence if the choice does not fit the
/// problem (Lattice FEM on particles off a lattice, a horizon factor below 1).
std::shared_ptr<AuxiliarySource> makeAuxiliarySource(Teuchos::RCP<const PeridynamicEvaluator> evaluator,
                                                     const Teuchos::ParameterList& twoStage);

}  // namespace perinox
