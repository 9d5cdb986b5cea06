// Damage bookkeeping (see DamageBookkeeping.hpp): broken bonds, detached particles, fragments.
#include "perinox/evaluator/DamageBookkeeping.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <algorithm>

namespace perinox {

DamageBookkeeping::DamageBookkeeping(Teuchos::RCP<const Teuchos::Comm<int>> comm, const ProblemSpec& problem,
                                     Model& model, const DofMaps& dofs, const LocalFamilies& families)
    : comm_(std::move(comm)), problem_(problem), model_(model), dofs_(dofs), families_(families) {
  // Stiffness of frozen (detached) DOFs: E V / dx^2 of a particle, so the frozen rows are neither
  // negligible nor dominant in the linear solves.
  // The volume of particle 0 (distributed: from the rank whose share holds it).
  double v0 = problem.disc.volume.front();
  if (problem.distributed) {
    const double mine = problem.globalId.front() == 0 ? v0 : -1.0;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(v0));
  }
  frozen_.stiffness = problem.stiffestModulus() * v0 / (problem.disc.dx * problem.disc.dx);
}

BreakReport DamageBookkeeping::breakBonds(const std::vector<double>& u, const double* xFree) {
  BreakReport rep;
  long long local = 0;
  if (model_.ductileCriterion()) {
    // The ends' plastic strains, owned ones from the trial state at u, the ghosts' from their
    // owners, so both ranks of a bond decide alike.
    local = model_.breakBonds(u, onLocalParticles(model_.trialPlasticStrain(u)));
  } else {
    local = model_.breakBonds(u);
  }
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(rep.brokenBonds));
  detachSingular(xFree, rep);
  return rep;
}

BreakReport DamageBookkeeping::breakMostStretched(const std::vector<double>& u, const double* xFree, double tol,
                                                  double& maxStretch) {
  BreakReport rep;
  const double mine = model_.maxIntactStretch(u);
  maxStretch = mine;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(maxStretch));
  if (!problem_.damage || !(maxStretch >= problem_.damageSpec.sMin)) return rep;
  long long local = model_.breakBondsAbove(u, maxStretch - tol);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(rep.brokenBonds));
  detachSingular(xFree, rep);
  return rep;
}

std::vector<std::pair<long long, long long>> DamageBookkeeping::ownedBrokenBonds() const {
  // The model's owned families start as built (families_) and only lose bonds.
  const LocalFamilies& F = families_;
  const LocalParticles& lp = model_.particles();
  std::vector<std::pair<long long, long long>> out;
  std::vector<long long> now;
  for (int i = 0; i < lp.numOwned; ++i) {
    const long long g = lp.globalId[i];
    now.clear();
    for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) now.push_back(lp.globalId[lp.famIndex[q]]);
    std::sort(now.begin(), now.end());
    for (auto q = F.ownedOffset[i]; q < F.ownedOffset[i + 1]; ++q) {
      const long long j = lp.globalId[F.ownedIndex[q]];
      if (!std::binary_search(now.begin(), now.end(), j)) out.emplace_back(g, j);
    }
  }
  return out;
}

std::vector<std::pair<long long, double>> DamageBookkeeping::ownedFrozenDofs() const {
  std::vector<std::pair<long long, double>> out;
  for (const auto& [lid, value] : frozen_.dofs) out.emplace_back(dofs_.ownedFreeDof[lid], value);
  return out;
}

void DamageBookkeeping::restore(const std::vector<std::pair<long long, long long>>& broken,
                                const std::vector<long long>& detached,
                                const std::vector<std::pair<long long, double>>& frozen) {
  std::vector<std::pair<long long, long long>> gone;
  gone.reserve(broken.size());
  for (auto [a, b] : broken) gone.emplace_back(std::min(a, b), std::max(a, b));
  std::sort(gone.begin(), gone.end());
  const LocalParticles& lp = model_.particles();
  if (!gone.empty())
    model_.removeBondsIf([&](int i, int j) {
      const long long a = lp.globalId[i], b = lp.globalId[j];
      return !std::binary_search(gone.begin(), gone.end(), std::make_pair(std::min(a, b), std::max(a, b)));
    });
  std::vector<long long> ids(detached);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  if (!ids.empty()) {
    model_.isolate(ids);
    model_.markDetached(ids);
  }
  detachedAll_ = ids;
  frozen_.dofs.clear();
  const int D = problem_.dim();
  for (const auto& [dof, value] : frozen) {
    const int lid = dofs_.ownedFreeLidOf(lp, dof, D);
    if (lid >= 0) frozen_.dofs.emplace_back(lid, value);
  }
}

void DamageBookkeeping::detachSingular(const double* xd, BreakReport& rep) {
  const int D = problem_.dim();
  // Isolates, marks detached and freezes (at x) the given particles (global ids, all ranks).
  auto detach = [&](const std::vector<long long>& ids) {
    model_.isolate(ids);
    model_.markDetached(ids);
    for (long long g : ids) {
      rep.detached.push_back(g);
      detachedAll_.push_back(g);
      const int l = model_.particles().ownedLocal(g);
      if (l < 0) continue;
      for (int c = 0; c < D; ++c) {
        const int lid = dofs_.overlapFreeLid[l * D + c];
        if (lid >= 0) frozen_.dofs.emplace_back(lid, xd[lid]);
      }
    }
  };
  for (int round = 0; round < 1000; ++round) {
    // Every particle that became singular on any rank (rare: after damage only).
    const auto ids = onAnyRank(model_.singularParticles());
    if (ids.empty()) break;
    detach(ids);
  }
  // Free-floating fragments: pieces the broken bonds have cut off from every prescribed DOF. Their
  // rigid-body motion makes the tangent singular and, unloaded, any position of theirs is an
  // equilibrium: a solver would either fail or let them drift (measured on the detaching strip:
  // its freed middle moved 0.094 mm sideways). They are removed like detached particles, frozen
  // where the last converged state left them, and reported.
  if (rep.brokenBonds > 0 || !rep.detached.empty()) {
    const auto frag = unanchoredParticles();
    if (!frag.empty()) {
      detach(frag);
      rep.fragmentParticles += static_cast<long long>(frag.size());
    }
  }
  std::sort(detachedAll_.begin(), detachedAll_.end());
}

std::vector<long long> DamageBookkeeping::unanchoredParticles() const {
  const LocalParticles& lp = model_.particles();
  // anchored[l]: particle l (owned or ghost) reaches a prescribed DOF through intact bonds. Spread
  // over the owned families to a fixed point on each rank, then to the ghosts by an Import, until
  // no rank anchors another particle.
  std::vector<char> anchored(lp.size(), 0);
  for (int l = 0; l < lp.numOwned; ++l) anchored[l] = problem_.fixedMask[problem_.index(lp.globalId[l])] != 0;
  long long before = -1;
  for (;;) {
    for (bool changed = true; changed;) {
      changed = false;
      for (int i = 0; i < lp.numOwned; ++i) {
        if (anchored[i]) continue;
        for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q)
          if (anchored[lp.famIndex[q]]) {
            anchored[i] = 1;
            changed = true;
            break;
          }
      }
    }
    long long mine = 0, total = 0;
    for (int i = 0; i < lp.numOwned; ++i) mine += anchored[i];
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(total));
    if (total == before) break;
    before = total;
    const std::vector<double> all = onLocalParticles(std::vector<double>(anchored.begin(), anchored.begin() + lp.numOwned));
    for (int l = lp.numOwned; l < lp.size(); ++l) anchored[l] = anchored[l] || all[l] > 0.5;
  }
  std::vector<long long> loose;
  for (int i = 0; i < lp.numOwned; ++i)
    if (!anchored[i] && !model_.detached(i)) loose.push_back(lp.globalId[i]);
  return onAnyRank(loose);
}

std::vector<double> DamageBookkeeping::onLocalParticles(const std::vector<double>& mine) const {
  // Component 0 of the all-DOF vectors carries the value; allImport takes it to the ghosts.
  const int D = problem_.dim();
  const LocalParticles& lp = model_.particles();
  TVector owned(dofs_.ownedAll), ghosted(dofs_.overlapAll);
  {
    auto od = owned.getDataNonConst();
    for (int i = 0; i < lp.numOwned; ++i) od[i * D] = mine[i];
  }
  ghosted.doImport(owned, *dofs_.allImport, Tpetra::INSERT);
  std::vector<double> all(mine.begin(), mine.end());
  all.resize(lp.size());
  auto gd = ghosted.getData();
  for (int l = lp.numOwned; l < lp.size(); ++l) all[l] = gd[l * D];
  return all;
}

std::vector<long long> DamageBookkeeping::onAnyRank(const std::vector<long long>& mine) const {
  // Every rank's list gathered to every rank: the lists are short (the particles detached in one
  // round), so this sends O(their length), not a flag per particle of the body.
  const int ranks = comm_->getSize();
  int count = static_cast<int>(mine.size());
  std::vector<int> counts(ranks, 0);
  Teuchos::gatherAll(*comm_, 1, &count, ranks, counts.data());
  const int most = *std::max_element(counts.begin(), counts.end());
  std::vector<long long> ids;
  if (most == 0) return ids;
  std::vector<long long> padded(static_cast<std::size_t>(most), -1), all(static_cast<std::size_t>(most) * ranks, -1);
  std::copy(mine.begin(), mine.end(), padded.begin());
  Teuchos::gatherAll(*comm_, most, padded.data(), static_cast<int>(all.size()), all.data());
  for (long long g : all)
    if (g >= 0) ids.push_back(g);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

}  // namespace perinox
