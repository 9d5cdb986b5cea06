#pragma once
// What the evaluator keeps of damage between load steps (defined in Damage.cpp): broken bonds
// (in the model's families), detached particles and their frozen DOFs, free-floating fragments,
// and their checkpoint form.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <utility>
#include <vector>

#include "perinox/evaluator/Assembly.hpp"

namespace perinox {

/// What one break did (global counts, the same on every rank).
struct BreakReport {
  long long brokenBonds = 0;             // bonds broken now (global)
  std::vector<long long> detached;       // particles detached now (global ids, all ranks)
  long long fragmentParticles = 0;       // of those, in free-floating fragments
};

class DamageBookkeeping {
 public:
  DamageBookkeeping(Teuchos::RCP<const Teuchos::Comm<int>> comm, const ProblemSpec& problem, Model& model,
                    const DofMaps& dofs, const LocalFamilies& families);
  /// After a converged step at the local displacements u (xFree: the owned free DOFs of the same
  /// state): breaks every bond with s >= s_cr, then detaches (isolates and freezes) every particle
  /// left with a singular shape tensor, repeating until none is, and every particle of a
  /// free-floating fragment (cut off from all prescribed DOFs).
  BreakReport breakBonds(const std::vector<double>& u, const double* xFree);
  /// A stall: breaks the intact bonds whose stretch is within tol of the largest one, if that one
  /// is in the softening band (s >= s_min; none otherwise), then detaches as breakBonds does.
  BreakReport breakMostStretched(const std::vector<double>& u, const double* xFree, double tol, double& maxStretch);
  /// Bonds of the owned particles broken so far, as (owned particle, neighbour) global ids.
  std::vector<std::pair<long long, long long>> ownedBrokenBonds() const;
  /// Frozen DOFs of the owned detached particles: (global free DOF id, frozen value).
  std::vector<std::pair<long long, double>> ownedFrozenDofs() const;
  /// Restores a checkpoint's damage (every rank, the same arguments).
  void restore(const std::vector<std::pair<long long, long long>>& broken, const std::vector<long long>& detached,
               const std::vector<std::pair<long long, double>>& frozen);
  const std::vector<long long>& detached() const { return detachedAll_; }
  const FrozenDofs& frozen() const { return frozen_; }

 private:
  void detachSingular(const double* xFree, BreakReport& rep);
  /// Attached particles (global ids, all ranks) that no chain of intact bonds connects to a
  /// particle with a prescribed DOF: free-floating fragments.
  std::vector<long long> unanchoredParticles() const;
  /// The union over all ranks of particle global ids, sorted (every rank gets the same list).
  std::vector<long long> onAnyRank(const std::vector<long long>& mine) const;
  /// A value per local particle (owned, then ghosts): `mine` for the owned ones, each ghost's
  /// from its owner (collective).
  std::vector<double> onLocalParticles(const std::vector<double>& mine) const;

  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  const ProblemSpec& problem_;
  Model& model_;
  const DofMaps& dofs_;
  const LocalFamilies& families_;
  std::vector<long long> detachedAll_;
  FrozenDofs frozen_;
};

}  // namespace perinox
