#pragma once
// The evaluator's Tpetra layer, apart from the Thyra adapter (PeridynamicEvaluator): the DOF
// numbering and maps (DofMaps), the Jacobian's graphs (JacobianGraphs), the assembly of element
// residuals and tangents into Tpetra objects (Assembler, with the TpetraSink of Assembly.cpp), and
// the tangent's inertia by a serial LDL^T (negativePivotCount). All of it in Assembly.cpp.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Export.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>
#include <string>
#include <utility>
#include <vector>

#include "perinox/evaluator/Problem.hpp"
#include "perinox/model/Partition.hpp"

namespace perinox {

using LO = int;
using GO = long long;
using TMap = Tpetra::Map<LO, GO>;
using TVector = Tpetra::Vector<double, LO, GO>;
using TCrsGraph = Tpetra::CrsGraph<LO, GO>;
using TCrsMatrix = Tpetra::CrsMatrix<double, LO, GO>;

/// The unknowns and the maps between them. The solution map holds the free DOFs of the owned
/// particles (prescribed DOFs are not unknowns), numbered rank by rank: rank r's come after those
/// of ranks 0..r-1, in its owned particles' order (component fastest), so no rank needs a
/// numbering of the whole body; a ghost's numbers come from its owner (imported). The "all" maps
/// hold every DOF, numbered particle * dim + c, of the owned (ownedAll) and of the local, ghosts
/// included (overlapAll), particles. allImport carries displacements to the ghosts, allExport
/// element residuals back to the owners (ADD).
struct DofMaps {
  DofMaps() = default;
  DofMaps(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const ProblemSpec& problem, const LocalParticles& particles);
  long long numFree = 0;
  std::vector<long long> overlapFreeGid;  // local (particle * dim + c) -> global free id or -1
  std::vector<int> overlapFreeLid;  // local (particle * dim + c) -> overlapFree lid or -1
  std::vector<GO> ownedFreeDof;     // owned free lid -> particle * dim + c
  /// The owned free lid of the DOF named dof (particle * dim + c), or -1 when that particle is
  /// not owned here or the DOF is prescribed (the inverse of ownedFreeDof).
  int ownedFreeLidOf(const LocalParticles& particles, long long dof, int dim) const {
    const int l = dof < 0 ? -1 : particles.ownedLocal(dof / dim);
    // owned particles' overlap lids are their owned lids
    return l < 0 ? -1 : overlapFreeLid[static_cast<std::size_t>(l) * dim + static_cast<int>(dof % dim)];
  }
  /// Global free ids of any DOFs (particle * dim + c, owned anywhere; collective), -1 where
  /// prescribed: what the Jacobian graph needs for its columns two horizons away.
  std::vector<long long> freeIdsOf(const std::vector<GO>& dofs) const;
  Teuchos::RCP<TVector> freeIdOwned;  // on ownedAll: the owned DOFs' global free ids, -1 prescribed
  Teuchos::RCP<const TMap> ownedFree, overlapFree, ownedAll, overlapAll;
  Teuchos::RCP<Tpetra::Import<LO, GO>> allImport;
  Teuchos::RCP<Tpetra::Export<LO, GO>> allExport;
  /// Rigid-body modes on the owned free DOFs (1 in 1D, 3 in 2D, 6 in 3D): rotations about the
  /// body's centroid, scaled by the horizon so every mode has entries of order one.
  Teuchos::RCP<Tpetra::MultiVector<double, LO, GO>> rigidBodyModes(const ProblemSpec& problem,
                                                                   const LocalParticles& particles) const;
};

/// The Jacobian's sparsity: owned rows (the owned matrix the solver gets), and the rows of ghost
/// particles' DOFs with overlap columns, whose values are exported (ADD) to their owners. Every
/// element {i} u H_i couples all its particles (full), or only those within one horizon of each
/// other (neighbours: the direct-neighbour preconditioner matrix).
struct JacobianGraphs {
  Teuchos::RCP<TCrsGraph> owned;
  Teuchos::RCP<TCrsGraph> ghost;
  Teuchos::RCP<TCrsMatrix> ghostMatrix;
  Teuchos::RCP<Tpetra::Export<LO, GO>> ghostExport;
  bool anyGhost = false;         // on any rank (not on one rank)
  std::vector<LO> ovColToOwned;  // overlap free lid -> column lid of the owned matrix (-1: none)
};

/// Detached particles' DOFs, frozen: f = stiffness (x - value), W_ii = stiffness.
struct FrozenDofs {
  std::vector<std::pair<int, double>> dofs;  // (owned free lid, frozen value)
  double stiffness = 1.0;
};

/// Runs the model's kernels over the rank's particles and sums the element residuals, tangents
/// and matrix-free products into Tpetra objects. Evaluation failures are agreed on by all ranks
/// before any collective, so every rank throws the same EvaluationError.
class Assembler {
 public:
  Assembler(Teuchos::RCP<const Teuchos::Comm<int>> comm, const ProblemSpec& problem, const Model& model,
            const DofMaps& dofs, const LocalFamilies& families);
  /// The graphs, built on first use.
  const JacobianGraphs& graphs(bool neighbours) const;
  /// The internal force on every owned DOF (owned particles * dim) at the local displacements u;
  /// with W (whose graph is graphs(neighbours).owned) also the Jacobian, frozen rows included.
  Teuchos::RCP<TVector> internalForce(const std::vector<double>& u, TCrsMatrix* W, bool neighbours,
                                      const FrozenDofs& frozen) const;
  /// y = (df/dx) v on the owned free DOFs, linearised at the local displacements u.
  void applyJacobian(const std::vector<double>& u, const double* v, double* y, const FrozenDofs& frozen) const;
  /// The diagonal of that operator on the owned free DOFs (y, their local order), from the
  /// element tangents' diagonal blocks: no matrix formed.
  void jacobianDiagonal(const std::vector<double>& u, double* y, const FrozenDofs& frozen) const;
  /// Bytes held by the sparse matrices built so far (owned and ghost rows; values, indices, rows).
  std::size_t matrixBytes() const;

 private:
  /// Sums an overlap vector (owned and ghost particles, all DOFs) onto the owners (owned: the
  /// Export's target, its owned entries come from the overlap's own) and copies the owned free
  /// DOFs' sums to y in their local order.
  void sumToOwnedFree(const TVector& overlap, TVector& owned, double* y) const;
  JacobianGraphs buildGraphs(bool neighbours) const;
  Teuchos::RCP<TCrsGraph> buildOwnedGraph(bool neighbours) const;
  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  const ProblemSpec& problem_;
  const Model& model_;
  const DofMaps& dofs_;
  const LocalFamilies& families_;
  mutable JacobianGraphs full_, nbr_;
  mutable Teuchos::RCP<TVector> jvOverlap_, jvOwned_;
};

/// Throws the same EvaluationError on every rank if any rank failed (the lowest failing particle
/// names it). Collective.
void agreeOnFailure(const Teuchos::Comm<int>& comm, int failed, std::string message, long long particle);

/// Number of negative pivots of W (its inertia, by Sylvester's law), from a sparse LDL^T of W
/// gathered on rank 0 (Eigen); -1 if W is not symmetric to 1e-8 or the factorisation fails.
/// Memory and time are those of a serial factorisation. Collective; every rank gets the count.
int negativePivotCount(const TCrsMatrix& W, const DofMaps& dofs, const Teuchos::Comm<int>& comm);

}  // namespace perinox
