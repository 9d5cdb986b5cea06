// The evaluator's Tpetra layer (see Assembly.hpp and JacobianOperators.hpp): DOF maps, graphs,
// the assembly sink, the matrix-free operators and the serial LDL^T.
#include "perinox/evaluator/Assembly.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Util.hpp>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "perinox/evaluator/JacobianOperators.hpp"

namespace perinox {

using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;

// ---------------------------------------------------------------------------------------------
// DofMaps
// ---------------------------------------------------------------------------------------------

DofMaps::DofMaps(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const ProblemSpec& P, const LocalParticles& lp) {
  const int D = P.dim();
  const int nLocal = lp.size();
  // The owned free DOFs: this rank's offset (the free DOFs of the ranks before it) + local order.
  long long mine = 0, upTo = 0;
  for (int l = 0; l < lp.numOwned; ++l)
    for (int c = 0; c < D; ++c) mine += !P.isFixed(static_cast<int>(lp.globalId[l]), c);
  Teuchos::scan(*comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(upTo));
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(numFree));
  long long next = upTo - mine;
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  std::vector<GO> ownedAllG, overlapAllG;
  for (int l = 0; l < nLocal; ++l)
    for (int c = 0; c < D; ++c) {
      overlapAllG.push_back(lp.globalId[l] * D + c);
      if (l < lp.numOwned) ownedAllG.push_back(lp.globalId[l] * D + c);
    }
  ownedAll = Teuchos::rcp(new TMap(static_cast<Tpetra::global_size_t>(P.particleCount()) * D,
                                   Teuchos::ArrayView<const GO>(ownedAllG), 0, comm));
  overlapAll = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(overlapAllG), 0, comm));
  allImport = Teuchos::rcp(new Tpetra::Import<LO, GO>(ownedAll, overlapAll));
  allExport = Teuchos::rcp(new Tpetra::Export<LO, GO>(overlapAll, ownedAll));
  // The owners' numbers, carried to the ghosts (exact as doubles below 2^53).
  freeIdOwned = Teuchos::rcp(new TVector(ownedAll));
  {
    auto v = freeIdOwned->getDataNonConst();
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c)
        v[l * D + c] = P.isFixed(static_cast<int>(lp.globalId[l]), c) ? -1.0 : static_cast<double>(next++);
  }
  TVector ghosted(overlapAll);
  ghosted.doImport(*freeIdOwned, *allImport, Tpetra::INSERT);
  const auto gv = ghosted.getData();
  overlapFreeGid.assign(static_cast<std::size_t>(nLocal) * D, -1);
  overlapFreeLid.assign(static_cast<std::size_t>(nLocal) * D, -1);
  std::vector<GO> ownedFreeG, overlapFreeG;
  for (int l = 0; l < nLocal; ++l)
    for (int c = 0; c < D; ++c) {
      const long long f = static_cast<long long>(gv[l * D + c]);
      overlapFreeGid[l * D + c] = f;
      if (f >= 0) {
        overlapFreeLid[l * D + c] = static_cast<int>(overlapFreeG.size());
        overlapFreeG.push_back(f);
        if (l < lp.numOwned) {
          ownedFreeG.push_back(f);
          ownedFreeDof.push_back(lp.globalId[l] * D + c);
        }
      }
    }
  ownedFree = Teuchos::rcp(new TMap(numFree, Teuchos::ArrayView<const GO>(ownedFreeG), 0, comm));
  overlapFree = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(overlapFreeG), 0, comm));
}

std::vector<long long> DofMaps::freeIdsOf(const std::vector<GO>& dofs) const {
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  auto target = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(dofs), 0, ownedAll->getComm()));
  TVector v(target);
  v.doImport(*freeIdOwned, Tpetra::Import<LO, GO>(ownedAll, target), Tpetra::INSERT);
  const auto d = v.getData();
  std::vector<long long> out(dofs.size());
  for (std::size_t k = 0; k < dofs.size(); ++k) out[k] = static_cast<long long>(d[k]);
  return out;
}

Teuchos::RCP<Tpetra::MultiVector<double, LO, GO>> DofMaps::rigidBodyModes(const ProblemSpec& problem,
                                                                          const LocalParticles& lp) const {
  const int D = problem.dim();
  const int nModes = rigidModeCount(D);
  auto B = Teuchos::rcp(new Tpetra::MultiVector<double, LO, GO>(ownedFree, nModes));
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  if (!problem.distributed) {
    for (const auto& X : problem.disc.X) c += X;
    c /= static_cast<double>(problem.disc.size());
  } else {  // the owned particles' sum over the ranks
    double mine[3] = {0, 0, 0}, all[3];
    for (int l = 0; l < lp.numOwned; ++l)
      for (int a = 0; a < 3; ++a) mine[a] += lp.X[l][a];
    Teuchos::reduceAll(*ownedAll->getComm(), Teuchos::REDUCE_SUM, 3, mine, all);
    c = Eigen::Vector3d(all[0], all[1], all[2]) / static_cast<double>(problem.particleCount());
  }
  const double L = problem.disc.horizon;
  for (int m = 0; m < nModes; ++m) {
    auto col = B->getDataNonConst(m);
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l) {
      const Eigen::Vector3d r = (lp.X[l] - c) / L;
      for (int a = 0; a < D; ++a)
        if (overlapFreeLid[l * D + a] >= 0) col[k++] = rigidModeValue(m, a, D, r);
    }
  }
  return B;
}

// ---------------------------------------------------------------------------------------------
// The assembly sink
// ---------------------------------------------------------------------------------------------

namespace {

/// Sums element contributions into the rank's overlapping residual and the Jacobian: rows of
/// owned DOFs straight into the owned matrix's values, rows of ghost DOFs into the ghost-row
/// matrix that is exported to their owners afterwards. For the owned rows, the element's columns
/// are sorted by the owned matrix's column lids once per element and merged with each particle's
/// sorted row; the rows of one particle's components share their column list (the graph gives
/// every component of a particle the same columns), so the merge is done once per particle.
/// Entries outside the graph (the neighbour graph) are dropped.
class TpetraSink final : public ElementSink {
 public:
  struct OwnedRows {
    const size_t* rowPtr = nullptr;
    const LO* cols = nullptr;
    double* values = nullptr;
    LO numRows = 0;                       // owned free DOFs: overlap lids below are owned rows
    LO numCols = 0;                       // columns of the owned matrix (its column map)
    const std::vector<LO>* ovColToOwned = nullptr;
    bool active = false;                  // a Jacobian is wanted (a rank may own no entries)
  };
  TpetraSink(int dim, double* r, const std::vector<int>& freeLid, const OwnedRows& owned, TCrsMatrix* ghost)
      : D_(dim), r_(r), freeLid_(freeLid), owned_(owned), ghost_(ghost) {}

  void add(const int* parts, int n, const double* re, const double* Ke) override {
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < D_; ++c) r_[parts[a] * D_ + c] += re[a * D_ + c];
    if (!Ke || !owned_.active) return;
    sortColumns(parts, n);
    const int nd = n * D_;
    for (int a = 0; a < n; ++a) {
      std::size_t mergedLength = static_cast<std::size_t>(-1);  // row length the offsets belong to
      for (int c = 0; c < D_; ++c) {
        const int row = freeLid_[parts[a] * D_ + c];
        if (row < 0) continue;
        const double* Krow = Ke + static_cast<std::size_t>(a * D_ + c) * nd;
        if (row < owned_.numRows) {
          addOwnedRow(row, Krow, mergedLength);
        } else if (ghost_) {
          for (std::size_t q = 0; q < cols_.size(); ++q) vals_[q] = Krow[pos_[q]];
          ghost_->sumIntoLocalValues(row - owned_.numRows, static_cast<LO>(cols_.size()), vals_.data(), cols_.data());
        }
      }
    }
  }

 private:
  /// The element's free columns (overlap lids and positions), and those of the owned matrix sorted.
  void sortColumns(const int* parts, int n) {
    cols_.clear();
    pos_.clear();
    sorted_.clear();
    for (int b = 0; b < n; ++b)
      for (int e = 0; e < D_; ++e) {
        const int lid = freeLid_[parts[b] * D_ + e];
        if (lid >= 0) {
          cols_.push_back(lid);
          pos_.push_back(b * D_ + e);
          const LO oc = (*owned_.ovColToOwned)[lid];
          if (oc >= 0) sorted_.emplace_back(oc, b * D_ + e);
        }
      }
    std::sort(sorted_.begin(), sorted_.end());
    vals_.resize(cols_.size());
    offsets_.resize(sorted_.size());
  }
  /// Adds one element row into an owned row of the matrix. The offset of each element column in
  /// the row comes from a column -> position table filled with the row's columns (once per
  /// particle: its D rows share their columns; `mergedLength` marks the row it was filled for).
  /// The table is never cleared: an entry is trusted only when the row holds that column there
  /// (a Neighbours graph drops some of an element's couplings).
  void addOwnedRow(int row, const double* Krow, std::size_t& mergedLength) {
    const size_t begin = owned_.rowPtr[row], length = owned_.rowPtr[row + 1] - begin;
    const LO* rc = owned_.cols + begin;
    if (length != mergedLength) {
      if (where_.size() < static_cast<std::size_t>(owned_.numCols)) where_.assign(owned_.numCols, 0);
      for (size_t k = 0; k < length; ++k) where_[rc[k]] = static_cast<LO>(k);
      for (std::size_t q = 0; q < sorted_.size(); ++q) {
        const LO col = sorted_[q].first, k = where_[col];
        offsets_[q] = static_cast<size_t>(k) < length && rc[k] == col ? static_cast<long>(k) : -1;
      }
      mergedLength = length;
    }
    double* v = owned_.values + begin;
    for (std::size_t q = 0; q < sorted_.size(); ++q)
      if (offsets_[q] >= 0) v[offsets_[q]] += Krow[sorted_[q].second];
  }

  int D_;
  double* r_;
  const std::vector<int>& freeLid_;
  OwnedRows owned_;
  TCrsMatrix* ghost_;
  std::vector<LO> cols_;
  std::vector<int> pos_;
  std::vector<std::pair<LO, int>> sorted_;  // (owned column lid, position in the element) by column
  std::vector<long> offsets_;               // position of each sorted column in the current row
  std::vector<LO> where_;                   // owned column lid -> its position in the last row filled
  std::vector<double> vals_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Assembler
// ---------------------------------------------------------------------------------------------

Assembler::Assembler(Teuchos::RCP<const Teuchos::Comm<int>> comm, const ProblemSpec& problem, const Model& model,
                     const DofMaps& dofs, const LocalFamilies& families)
    : comm_(std::move(comm)), problem_(problem), model_(model), dofs_(dofs), families_(families) {}

const JacobianGraphs& Assembler::graphs(bool neighbours) const {
  JacobianGraphs& g = neighbours ? nbr_ : full_;
  if (g.owned.is_null()) g = buildGraphs(neighbours);
  return g;
}

JacobianGraphs Assembler::buildGraphs(bool neighbours) const {
  const Discretization& d = problem_.disc;
  const int D = problem_.dim();
  const LocalParticles& lp = model_.particles();
  const int nLocal = lp.size();
  const std::vector<int>& ofl = dofs_.overlapFreeLid;
  // With neighbours, a pair of particles is coupled only when they are within one horizon of
  // each other (the bonds themselves), not through a shared family member (two horizons).
  const double reach2 = d.horizon * d.horizon * (1.0 + 1e-10);
  auto near = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return !neighbours || (a - b).squaredNorm() <= reach2;
  };
  JacobianGraphs g;
  // Overlapping graph: every owned element {i} u H_i couples its particles.
  std::vector<std::vector<int>> adj(nLocal);
  for (int i = 0; i < lp.numOwned; ++i) {
    std::vector<int> parts{i};
    for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) parts.push_back(lp.famIndex[q]);
    for (int a : parts)  // only the ghost rows are built here (owned rows: buildOwnedGraph)
      if (a >= lp.numOwned)
        for (int b : parts)
          if (near(lp.X[a], lp.X[b])) adj[a].push_back(b);
  }
  // Ghost-row graph: the rows of the ghost particles' free DOFs (overlap lids from the owned
  // count on), in the overlap's order; its column map is the overlap map.
  const LO nOwnedFree = static_cast<LO>(dofs_.ownedFree->getNodeNumElements());
  const LO nOverlapFree = static_cast<LO>(dofs_.overlapFree->getNodeNumElements());
  std::vector<GO> ghostRows;
  for (LO r = nOwnedFree; r < nOverlapFree; ++r) ghostRows.push_back(dofs_.overlapFree->getGlobalElement(r));
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  auto ghostMap = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(ghostRows), 0, comm_));
  std::vector<size_t> nnzGhost(ghostRows.size(), 0);
  for (int l = lp.numOwned; l < nLocal; ++l) {
    auto& v = adj[l];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    size_t cnt = 0;
    for (int q : v)
      for (int c = 0; c < D; ++c) cnt += ofl[q * D + c] >= 0;
    for (int c = 0; c < D; ++c)
      if (ofl[l * D + c] >= 0) nnzGhost[ofl[l * D + c] - nOwnedFree] = cnt;
  }
  g.ghost = Teuchos::rcp(new TCrsGraph(ghostMap, dofs_.overlapFree, Teuchos::ArrayView<const size_t>(nnzGhost)));
  std::vector<LO> cols;
  for (int l = lp.numOwned; l < nLocal; ++l) {
    cols.clear();
    for (int q : adj[l])
      for (int c = 0; c < D; ++c)
        if (ofl[q * D + c] >= 0) cols.push_back(ofl[q * D + c]);
    for (int c = 0; c < D; ++c)
      if (ofl[l * D + c] >= 0) g.ghost->insertLocalIndices(ofl[l * D + c] - nOwnedFree, Teuchos::ArrayView<const LO>(cols));
  }
  adj.clear();
  adj.shrink_to_fit();
  g.ghost->fillComplete(dofs_.ownedFree, dofs_.ownedFree);
  int mine = ghostRows.empty() ? 0 : 1, any = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(any));
  g.anyGhost = any != 0;
  g.ghostExport = Teuchos::rcp(new Tpetra::Export<LO, GO>(ghostMap, dofs_.ownedFree));
  g.owned = buildOwnedGraph(neighbours);
  g.ovColToOwned.assign(nOverlapFree, -1);
  for (LO c = 0; c < nOverlapFree; ++c) {
    const LO k = g.owned->getColMap()->getLocalElement(dofs_.overlapFree->getGlobalElement(c));
    if (k != Teuchos::OrdinalTraits<LO>::invalid()) g.ovColToOwned[c] = k;
  }
  g.ghostMatrix = Teuchos::rcp(new TCrsMatrix(g.ghost));
  g.ghostMatrix->fillComplete(dofs_.ownedFree, dofs_.ownedFree);
  return g;
}

// The owned graph, from the families as built (the owned particles' and their ghosts'): row
// particle p couples to every particle of every element that contains p, i.e. of {i} u H_i for
// i in {p} u H_p (only those within one horizon of p with neighbours). The graph is made in local
// indices directly, with the column map fillComplete would make (the domain map's columns in its
// order, then the remote ones grouped by owning rank with Tpetra::sort2), so its entries and their order are those of
// a graph filled by global indices, without Tpetra's per-row insertion.
Teuchos::RCP<TCrsGraph> Assembler::buildOwnedGraph(bool neighbours) const {
  const Discretization& d = problem_.disc;
  const int D = problem_.dim();
  const double reach2 = d.horizon * d.horizon * (1.0 + 1e-10);
  auto near = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return !neighbours || (a - b).squaredNorm() <= reach2;
  };
  const LocalParticles& lp = model_.particles();
  const LocalFamilies& F = families_;
  // Particles of each owned particle's rows (ids ascending): partNbr[partPtr[l] .. partPtr[l + 1]).
  std::vector<std::size_t> partPtr{0};
  std::vector<long long> partNbr;
  std::vector<long long> S;
  auto addElement = [&](int local) {  // {i} u H_i of local particle i
    S.push_back(lp.globalId[local]);
    if (local < lp.numOwned) {
      for (auto q = F.ownedOffset[local]; q < F.ownedOffset[local + 1]; ++q) S.push_back(lp.globalId[F.ownedIndex[q]]);
    } else {
      const int k = local - lp.numOwned;
      S.insert(S.end(), F.ghostMembers.begin() + F.ghostOffset[k], F.ghostMembers.begin() + F.ghostOffset[k + 1]);
    }
  };
  for (int l = 0; l < lp.numOwned; ++l) {
    const long long p = lp.globalId[l];
    S.clear();
    addElement(l);
    for (auto q = F.ownedOffset[l]; q < F.ownedOffset[l + 1]; ++q) addElement(F.ownedIndex[q]);
    std::sort(S.begin(), S.end());
    S.erase(std::unique(S.begin(), S.end()), S.end());
    for (long long s : S)
      if (!neighbours || near(d.X[problem_.index(p)], d.X[problem_.index(s)])) partNbr.push_back(s);
    partPtr.push_back(partNbr.size());
  }
  // Their free ids, from their owners (the particles two horizons away need not be local).
  std::vector<long long> reach(partNbr);
  std::sort(reach.begin(), reach.end());
  reach.erase(std::unique(reach.begin(), reach.end()), reach.end());
  std::vector<GO> reachDofs;
  reachDofs.reserve(reach.size() * D);
  for (long long s : reach)
    for (int c = 0; c < D; ++c) reachDofs.push_back(s * D + c);
  const std::vector<long long> reachFree = dofs_.freeIdsOf(reachDofs);
  auto freeOf = [&](long long s, int c) {
    const auto k = std::lower_bound(reach.begin(), reach.end(), s) - reach.begin();
    return reachFree[static_cast<std::size_t>(k) * D + c];
  };
  std::vector<GO> partCols;  // the same, as free ids
  std::vector<std::size_t> colPtr{0};
  for (int l = 0; l < lp.numOwned; ++l) {
    for (std::size_t q = partPtr[l]; q < partPtr[l + 1]; ++q)
      for (int c = 0; c < D; ++c) {
        const long long f = freeOf(partNbr[q], c);
        if (f >= 0) partCols.push_back(f);
      }
    colPtr.push_back(partCols.size());
  }
  partPtr.swap(colPtr);
  std::vector<long long>().swap(partNbr);
  const auto& rowMap = dofs_.ownedFree;
  const LO nRows = static_cast<LO>(rowMap->getNodeNumElements());
  // The column map: the row map's columns present, in its order, then the remote ones.
  std::vector<char> present(static_cast<std::size_t>(nRows), 0);
  std::vector<GO> remote;
  for (GO g : partCols) {
    const LO k = rowMap->getLocalElement(g);
    if (k != Teuchos::OrdinalTraits<LO>::invalid()) present[k] = 1;
    else remote.push_back(g);
  }
  std::sort(remote.begin(), remote.end());
  remote.erase(std::unique(remote.begin(), remote.end()), remote.end());
  std::vector<int> owner(remote.size());
  rowMap->getRemoteIndexList(Teuchos::ArrayView<const GO>(remote), Teuchos::ArrayView<int>(owner));
  // Grouped by owner with Tpetra's own sort2, as its column map does (the order within a group
  // is that sort's, not necessarily ascending).
  Tpetra::sort2(owner.begin(), owner.end(), remote.begin());
  std::vector<GO> colGids;
  for (LO k = 0; k < nRows; ++k)
    if (present[k]) colGids.push_back(rowMap->getGlobalElement(k));
  colGids.insert(colGids.end(), remote.begin(), remote.end());
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  auto colMap = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(colGids), 0, comm_));
  // Rows in the row map's order (owned particles ascending, then components), local columns sorted.
  Teuchos::ArrayRCP<size_t> rowPtr(static_cast<std::size_t>(nRows) + 1, 0);
  std::size_t entries = 0;
  for (int l = 0; l < lp.numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (dofs_.overlapFreeGid[l * D + c] >= 0) entries += partPtr[l + 1] - partPtr[l];
  Teuchos::ArrayRCP<LO> colInd(entries);
  std::vector<LO> lids;
  LO row = 0;
  std::size_t at = 0;
  for (int l = 0; l < lp.numOwned; ++l) {
    lids.clear();
    for (std::size_t q = partPtr[l]; q < partPtr[l + 1]; ++q) lids.push_back(colMap->getLocalElement(partCols[q]));
    std::sort(lids.begin(), lids.end());
    for (int c = 0; c < D; ++c) {
      const long long f = dofs_.overlapFreeGid[l * D + c];
      if (f < 0) continue;
      if (row >= nRows || rowMap->getGlobalElement(row) != f)
        throw std::logic_error("perinox: the Jacobian graph's rows do not follow the solution map");
      std::copy(lids.begin(), lids.end(), colInd.begin() + static_cast<std::ptrdiff_t>(at));
      at += lids.size();
      rowPtr[++row] = at;
    }
  }
  if (row != nRows) throw std::logic_error("perinox: the Jacobian graph has fewer rows than the solution map");
  auto owned = Teuchos::rcp(new TCrsGraph(rowMap, colMap, rowPtr, colInd));
  owned->expertStaticFillComplete(rowMap, rowMap);
  return owned;
}

std::size_t Assembler::matrixBytes() const {
  std::size_t b = 0;
  for (const JacobianGraphs* g : {&full_, &nbr_}) {
    if (g->owned.is_null()) continue;
    // values (8 B) and local column indices (4 B) per entry, row offsets (8 B) per row, for the
    // owned and the ghost-row matrix (the graphs share their indices with the matrices).
    for (const auto& gr : {g->owned, g->ghost})
      b += gr->getNodeNumEntries() * (8 + 4) + (gr->getNodeNumRows() + 1) * 8;
  }
  return b;
}

Teuchos::RCP<TVector> Assembler::internalForce(const std::vector<double>& u, TCrsMatrix* W, bool neighbours,
                                               const FrozenDofs& frozen) const {
  const JacobianGraphs* g = W ? &graphs(neighbours) : nullptr;
  TCrsMatrix* ghost = g && g->anyGhost ? g->ghostMatrix.get() : nullptr;
  const auto& ownedFree = dofs_.ownedFree;
  TVector rOv(dofs_.overlapAll);
  rOv.putScalar(0.0);
  TpetraSink::OwnedRows rows;
  typename TCrsMatrix::local_matrix_host_type local;
  if (W) {
    W->resumeFill();
    W->setAllToScalar(0.0);
    local = W->getLocalMatrixHost();
    rows.rowPtr = local.graph.row_map.data();
    rows.cols = local.graph.entries.data();
    rows.values = local.values.data();
    rows.numRows = static_cast<LO>(ownedFree->getNodeNumElements());
    rows.numCols = static_cast<LO>(W->getColMap()->getNodeNumElements());
    rows.ovColToOwned = &g->ovColToOwned;
    rows.active = true;
    if (ghost) {
      ghost->resumeFill();
      ghost->setAllToScalar(0.0);
    }
  }
  // An EvaluationError on one rank must reach all ranks, or the others hang in the Export.
  int failed = 0;
  std::string message;
  long long particle = -1;
  {
    auto rd = rOv.getDataNonConst();
    TpetraSink sink(problem_.dim(), rd.getRawPtr(), dofs_.overlapFreeLid, rows, ghost);
    try {
      model_.evaluate(u, sink, W != nullptr);
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  if (ghost) ghost->fillComplete(ownedFree, ownedFree);
  agreeOnFailure(*comm_, failed, message, particle);
  auto r = Teuchos::rcp(new TVector(dofs_.ownedAll));
  r->doExport(rOv, *dofs_.allExport, Tpetra::ADD);
  if (W) {
    if (ghost) W->doExport(*ghost, *g->ghostExport, Tpetra::ADD);
    for (const auto& [lid, value] : frozen.dofs) {
      (void)value;
      const LO col = W->getColMap()->getLocalElement(ownedFree->getGlobalElement(lid));
      W->sumIntoLocalValues(lid, 1, &frozen.stiffness, &col);
    }
    W->fillComplete(ownedFree, ownedFree);
  }
  return r;
}

void Assembler::applyJacobian(const std::vector<double>& u, const double* v, double* y, const FrozenDofs& frozen) const {
  const int D = problem_.dim();
  const LocalParticles& lp = model_.particles();
  const std::vector<int>& ofl = dofs_.overlapFreeLid;
  // Direction on all owned DOFs (prescribed ones do not move), then onto the ghosts.
  TVector vOwned(dofs_.ownedAll);
  {
    auto vd = vOwned.getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c) vd[l * D + c] = ofl[l * D + c] >= 0 ? v[k++] : 0.0;
  }
  if (!jvOverlap_) {
    jvOverlap_ = Teuchos::rcp(new TVector(dofs_.overlapAll));
    jvOwned_ = Teuchos::rcp(new TVector(dofs_.ownedAll));
  }
  TVector vOv(dofs_.overlapAll);
  vOv.doImport(vOwned, *dofs_.allImport, Tpetra::INSERT);
  jvOverlap_->putScalar(0.0);
  int failed = 0;
  std::string message;
  long long particle = -1;
  {
    auto vd = vOv.getData();
    const std::vector<double> vl(vd.begin(), vd.end());
    auto jd = jvOverlap_->getDataNonConst();
    try {
      model_.applyTangent(u, vl, jd.getRawPtr());
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  agreeOnFailure(*comm_, failed, message, particle);
  sumToOwnedFree(*jvOverlap_, *jvOwned_, y);
  for (const auto& [lid, value] : frozen.dofs) {
    (void)value;
    y[lid] = frozen.stiffness * v[lid];
  }
}

void Assembler::sumToOwnedFree(const TVector& overlap, TVector& owned, double* y) const {
  owned.doExport(overlap, *dofs_.allExport, Tpetra::ADD);
  const int D = problem_.dim();
  const int numOwned = model_.particles().numOwned;
  const std::vector<int>& ofl = dofs_.overlapFreeLid;
  auto od = owned.getData();
  LO k = 0;
  for (int l = 0; l < numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (ofl[l * D + c] >= 0) y[k++] = od[l * D + c];
}

void Assembler::jacobianDiagonal(const std::vector<double>& u, double* y, const FrozenDofs& frozen) const {
  TVector dOv(dofs_.overlapAll), dOwned(dofs_.ownedAll);
  int failed = 0;
  std::string message;
  long long particle = -1;
  {
    auto dd = dOv.getDataNonConst();
    try {
      model_.addJacobianDiagonal(u, dd.getRawPtr());
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  agreeOnFailure(*comm_, failed, message, particle);
  sumToOwnedFree(dOv, dOwned, y);
  for (const auto& [lid, value] : frozen.dofs) {
    (void)value;
    y[lid] = frozen.stiffness;
  }
}

void agreeOnFailure(const Teuchos::Comm<int>& comm, int failed, std::string message, long long particle) {
  int anyFailed = 0;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, failed, Teuchos::outArg(anyFailed));
  if (!anyFailed) return;
  // Report the lowest-ranked failure so every rank throws the same sentence.
  long long pmin = failed ? particle : std::numeric_limits<long long>::max();
  long long pglob = pmin;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, pmin, Teuchos::outArg(pglob));
  if (!failed || particle != pglob) {
    std::ostringstream s;
    s << "evaluation failed at particle " << pglob;
    message = s.str();
  }
  throw EvaluationError(message, pglob);
}

// ---------------------------------------------------------------------------------------------
// The matrix-free operators
// ---------------------------------------------------------------------------------------------

void JacobianOperator::apply(const TMultiVector& X, TMultiVector& Y, Teuchos::ETransp mode, double alpha,
                             double beta) const {
  TEUCHOS_TEST_FOR_EXCEPTION(mode != Teuchos::NO_TRANS, std::logic_error, "the matrix-free Jacobian has no transpose product");
  TEUCHOS_TEST_FOR_EXCEPTION(u_.empty(), std::logic_error, "the matrix-free Jacobian was applied before evaluation");
  const size_t n = X.getLocalLength();
  std::vector<double> y(n);
  for (size_t k = 0; k < X.getNumVectors(); ++k) {
    auto xd = X.getData(k);
    assembler_.applyJacobian(u_, xd.getRawPtr(), y.data(), frozen_);
    auto yd = Y.getDataNonConst(k);
    for (size_t r = 0; r < n; ++r) yd[r] = (beta == 0.0 ? 0.0 : beta * yd[r]) + alpha * y[r];
  }
}

void JacobianOperator::getDiagonal(TMultiVector& d) const {
  auto dd = d.getDataNonConst(0);
  assembler_.jacobianDiagonal(u_, dd.getRawPtr(), frozen_);
}

void DifferenceJacobianOperator::setState(const Thyra::VectorBase<double>& x) {
  x_ = x.clone_v();
  f0_ = Thyra::createMember(x.space());
  evalF(*x_, *f0_);
}

void DifferenceJacobianOperator::apply(const TMultiVector& X, TMultiVector& Y, Teuchos::ETransp mode, double alpha,
                                       double beta) const {
  TEUCHOS_TEST_FOR_EXCEPTION(mode != Teuchos::NO_TRANS, std::logic_error, "the Jacobian-free operator has no transpose product");
  TEUCHOS_TEST_FOR_EXCEPTION(x_.is_null(), std::logic_error, "the Jacobian-free operator was applied before evaluation");
  const double scale = std::max(Thyra::norm_inf(*x_), dx_);
  auto xp = Thyra::createMember(x_->space());
  auto fp = Thyra::createMember(x_->space());
  for (size_t k = 0; k < X.getNumVectors(); ++k) {
    auto v = Thyra::createVector<double, LO, GO, Node>(
        Teuchos::rcp_const_cast<Tpetra::Vector<double, LO, GO, Node>>(X.getVector(k)), x_->space());
    const double vinf = Thyra::norm_inf(*v);
    auto yk = Y.getVectorNonConst(k);
    if (vinf == 0.0) {
      yk->scale(beta);
      continue;
    }
    const double h = lambda_ * scale / vinf;
    Thyra::V_StVpV(xp.ptr(), h, *v, *x_);
    evalF(*xp, *fp);
    Thyra::Vp_StV(fp.ptr(), -1.0, *f0_);
    auto fpt = TOE::getConstTpetraVector(fp);
    yk->update(alpha / h, *fpt, beta);
  }
}

void DifferenceJacobianOperator::evalF(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& f) const {
  auto in = model_.createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto out = model_.createOutArgs();
  out.set_f(Teuchos::rcpFromRef(f));
  model_.evalModel(in, out);
}

// ---------------------------------------------------------------------------------------------
// The tangent's inertia (serial LDL^T)
// ---------------------------------------------------------------------------------------------

int negativePivotCount(const TCrsMatrix& W, const DofMaps& dofs, const Teuchos::Comm<int>& comm) {
  const long long numFree = dofs.numFree;
  const auto commRcp = W.getComm();
  // Gather every row on rank 0.
  std::vector<GO> mine;
  if (comm.getRank() == 0)
    for (long long g = 0; g < numFree; ++g) mine.push_back(g);
  auto rootMap = Teuchos::rcp(new TMap(numFree, Teuchos::ArrayView<const GO>(mine), 0, commRcp));
  Tpetra::Import<LO, GO> imp(dofs.ownedFree, rootMap);
  TCrsMatrix G(rootMap, 0);
  G.doImport(W, imp, Tpetra::INSERT);
  G.fillComplete(rootMap, rootMap);
  int result = 0;
  if (comm.getRank() == 0) {
    std::vector<Eigen::Triplet<double>> t;
    const auto n = static_cast<long long>(numFree);
    Teuchos::Array<GO> cols;
    Teuchos::Array<double> vals;
    double maxAbs = 0;
    for (LO r = 0; r < static_cast<LO>(n); ++r) {
      const GO gr = rootMap->getGlobalElement(r);
      const size_t nnz = G.getNumEntriesInGlobalRow(gr);
      cols.resize(nnz);
      vals.resize(nnz);
      size_t got = 0;
      G.getGlobalRowCopy(gr, cols(), vals(), got);
      for (size_t k = 0; k < got; ++k) {
        t.emplace_back(static_cast<int>(gr), static_cast<int>(cols[k]), vals[k]);
        maxAbs = std::max(maxAbs, std::abs(vals[k]));
      }
    }
    Eigen::SparseMatrix<double> A(static_cast<int>(n), static_cast<int>(n));
    A.setFromTriplets(t.begin(), t.end());
    Eigen::SparseMatrix<double> At = A.transpose();
    Eigen::SparseMatrix<double> diff = A - At;
    const double asym = diff.nonZeros() ? diff.coeffs().cwiseAbs().maxCoeff() : 0.0;
    if (asym > 1e-8 * maxAbs) {
      result = -1;
    } else {
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
      if (ldlt.info() != Eigen::Success) {
        result = -1;
      } else {
        const auto d = ldlt.vectorD();
        for (int i = 0; i < d.size(); ++i) result += d[i] < 0;
      }
    }
  }
  Teuchos::broadcast(comm, 0, Teuchos::outArg(result));
  return result;
}

}  // namespace perinox
