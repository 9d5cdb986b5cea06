// Auxiliary operators of the two-stage preconditioner: lattice finite elements, short horizon.
#include "perinox/solver/AuxiliaryOperators.hpp"

#include "perinox/evaluator/PeridynamicEvaluator.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace perinox {

namespace {
using LO = int;
using GO = long long;
using Node = Tpetra::Map<LO, GO>::node_type;
using TMap = Tpetra::Map<LO, GO, Node>;
using MV = Tpetra::MultiVector<double, LO, GO, Node>;
using TVector = Tpetra::Vector<double, LO, GO, Node>;
using TCrsMatrix = Tpetra::CrsMatrix<double, LO, GO, Node>;
using Teuchos::RCP;
using Teuchos::rcp;

/// The all-DOF layout of an evaluator's owned particles (gid = particle * dim + component), with
/// its rigid-body modes and coordinates: what every auxiliary operator shares.
AuxiliaryOperator allDofLayout(const PeridynamicEvaluator& ev, RCP<const TMap>& allMap) {
  const ProblemSpec& P = ev.problem();
  const int D = P.dim();
  const auto comm = ev.comm();
  std::vector<GO> all, nodes;
  for (long long p : ev.ownedParticles()) {
    nodes.push_back(p);
    for (int c = 0; c < D; ++c) all.push_back(p * D + c);
  }
  const auto inv = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  allMap = rcp(new TMap(inv, all.data(), all.size(), 0, comm));
  auto nodeMap = rcp(new TMap(inv, nodes.data(), nodes.size(), 0, comm));
  AuxiliaryOperator a;
  a.blockSize = D;
  a.damage = static_cast<bool>(P.damage);
  auto fm = ev.ownedFreeMap();
  a.freeToAll.assign(fm->getNodeNumElements(), -1);
  const auto& owned = ev.ownedParticles();
  for (std::size_t l = 0; l < owned.size(); ++l)
    for (int c = 0; c < D; ++c)
      if (ev.freeDof(owned[l], c) >= 0)
        a.freeToAll[fm->getLocalElement(ev.freeDof(owned[l], c))] = static_cast<LO>(l * D + c);
  // The body's centroid (owned particles, summed over ranks) and the modes about it, scaled by
  // the horizon so that every column has entries of order one; non-zero on prescribed rows too
  // (a zero column there made MueLu throw, docs/trilinos-notes.md).
  double local[4] = {0, 0, 0, 0}, global[4];
  for (long long p : ev.ownedParticles()) {
    for (int d = 0; d < 3; ++d) local[d] += P.disc.X[P.index(p)][d];
    local[3] += 1;
  }
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 4, local, global);
  const Eigen::Vector3d centre(global[0] / global[3], global[1] / global[3], global[2] / global[3]);
  const double L = P.disc.horizon;
  const int nModes = rigidModeCount(D);
  auto B = rcp(new MV(allMap, nModes));
  auto C = rcp(new MV(nodeMap, D));
  for (int m = 0; m < nModes; ++m) {
    auto col = B->getDataNonConst(m);
    LO k = 0;
    for (long long p : ev.ownedParticles()) {
      const Eigen::Vector3d r = (P.disc.X[P.index(p)] - centre) / L;
      for (int a = 0; a < D; ++a) col[k++] = rigidModeValue(m, a, D, r);
    }
  }
  for (int d = 0; d < D; ++d) {
    auto col = C->getDataNonConst(d);
    LO k = 0;
    for (long long p : ev.ownedParticles()) col[k++] = P.disc.X[P.index(p)][d];
  }
  a.nullspace = B;
  a.coordinates = C;
  return a;
}

/// The lowest coordinate of every particle (per axis), and each particle's lattice indices.
Eigen::Vector3d lowestCorner(const Discretization& d) {
  Eigen::Vector3d lo = d.X.empty() ? Eigen::Vector3d::Zero() : d.X[0];
  for (const auto& X : d.X) lo = lo.cwiseMin(X);
  return lo;
}

// ---------------------------------------------------------------------------------------------
// Lattice FEM

}  // namespace

Eigen::MatrixXd latticeElementStiffness(int D, double h, const MaterialSpec& m, double thickness) {
  const double E = m.E, nu = m.nu;
  if (D == 1) {
    Eigen::MatrixXd K(2, 2);
    const double k = E * thickness / h;  // thickness: the 1D cross-section area
    K << k, -k, -k, k;
    return K;
  }
  Eigen::MatrixXd C;
  if (D == 2) {
    C = Eigen::MatrixXd::Zero(3, 3);
    if (m.planar == PlanarMode::PlaneStress) {
      const double f = E / (1 - nu * nu);
      C << f, f * nu, 0, f * nu, f, 0, 0, 0, f * (1 - nu) / 2;
    } else {
      const double f = E / ((1 + nu) * (1 - 2 * nu));
      C << f * (1 - nu), f * nu, 0, f * nu, f * (1 - nu), 0, 0, 0, f * (1 - 2 * nu) / 2;
    }
  } else {
    C = Eigen::MatrixXd::Zero(6, 6);
    const double lam = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) C(i, j) = lam;
      C(i, i) += 2 * mu;
      C(3 + i, 3 + i) = mu;
    }
  }
  const int nn = 1 << D, nd = nn * D, ns = D == 2 ? 3 : 6;
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nd, nd);
  const double g = 1.0 / std::sqrt(3.0);
  for (int q = 0; q < nn; ++q) {
    const double xi[3] = {(q & 1) ? g : -g, ((q >> 1) & 1) ? g : -g, ((q >> 2) & 1) ? g : -g};
    Eigen::MatrixXd dN(nn, D);  // shape-function derivatives in physical coordinates
    for (int a = 0; a < nn; ++a) {
      double s[3];
      for (int d = 0; d < 3; ++d) s[d] = ((a >> d) & 1) ? 1.0 : -1.0;
      for (int d = 0; d < D; ++d) {
        double v = s[d] / h;
        for (int e = 0; e < D; ++e)
          if (e != d) v *= 0.5 * (1 + s[e] * xi[e]);
        dN(a, d) = v;
      }
    }
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(ns, nd);
    for (int a = 0; a < nn; ++a) {
      if (D == 2) {
        B(0, a * 2) = dN(a, 0);
        B(1, a * 2 + 1) = dN(a, 1);
        B(2, a * 2) = dN(a, 1);
        B(2, a * 2 + 1) = dN(a, 0);
      } else {
        for (int d = 0; d < 3; ++d) B(d, a * 3 + d) = dN(a, d);
        B(3, a * 3 + 1) = dN(a, 2);  // yz
        B(3, a * 3 + 2) = dN(a, 1);
        B(4, a * 3 + 0) = dN(a, 2);  // xz
        B(4, a * 3 + 2) = dN(a, 0);
        B(5, a * 3 + 0) = dN(a, 1);  // xy
        B(5, a * 3 + 1) = dN(a, 0);
      }
    }
    const double w = std::pow(h / 2, D) * (D == 2 ? thickness : 1.0);
    K += w * B.transpose() * C * B;
  }
  return K;
}

namespace {

class LatticeFemSource final : public AuxiliarySource {
 public:
  // The evaluator is held weakly: it holds the linear solver that holds this source.
  explicit LatticeFemSource(const RCP<const PeridynamicEvaluator>& ev) : ev_(ev.create_weak()) {
    RCP<const TMap> allMap;
    op_ = allDofLayout(*ev_, allMap);
    op_.matrix = assemble(allMap);
    op_.version = 1;
  }
  const AuxiliaryOperator& current() override { return op_; }
  std::string description() const override {
    std::ostringstream s;
    s << "lattice finite-element stiffness, " << op_.matrix->getGlobalNumRows() << " rows";
    return s.str();
  }

 private:
  RCP<const TCrsMatrix> assemble(const RCP<const TMap>& allMap) const {
    const PeridynamicEvaluator& ev = *ev_;
    const ProblemSpec& P = ev.problem();
    const int D = P.dim();
    const double h = P.disc.dx;
    const Eigen::Vector3d lo = lowestCorner(P.disc);
    std::array<long long, 3> n{{1, 1, 1}};
    std::vector<std::array<long long, 3>> ijk(P.disc.size());
    for (int p = 0; p < P.disc.size(); ++p)
      for (int d = 0; d < 3; ++d) {
        ijk[p][d] = d < D ? std::llround((P.disc.X[p][d] - lo[d]) / h) : 0;
        n[d] = std::max(n[d], ijk[p][d] + 1);
      }
    std::unordered_map<long long, int> site;  // lattice site -> particle
    site.reserve(P.disc.size());
    auto key = [&](long long i, long long j, long long k) { return (k * n[1] + j) * n[0] + i; };
    for (int p = 0; p < P.disc.size(); ++p) site[key(ijk[p][0], ijk[p][1], ijk[p][2])] = p;
    auto at = [&](long long i, long long j, long long k) -> int {
      if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return -1;
      auto it = site.find(key(i, j, k));
      return it == site.end() ? -1 : it->second;
    };
    const Eigen::MatrixXd Ke = latticeElementStiffness(D, h, P.material, P.disc.thickness);
    // Blocks: each block's element stiffness; a cell takes the mean of its corners' (below).
    std::vector<Eigen::MatrixXd> blockKe;
    std::vector<int> blockOf;
    if (!P.blocks.empty()) {
      for (const BlockSpec& blk : P.blocks) blockKe.push_back(latticeElementStiffness(D, h, blk.material, P.disc.thickness));
      blockOf = P.blockIndex();
    }
    const int nn = 1 << D;
    // Prescribed rows: a unit diagonal scaled like an interior node's diagonal.
    std::vector<double> diag(D);
    for (int c = 0; c < D; ++c) diag[c] = nn * Ke(c, c);
    auto M = rcp(new TCrsMatrix(allMap, D == 1 ? 3 : (D == 2 ? 18 : 81)));
    std::map<GO, double> row[3];
    std::vector<GO> cols;
    std::vector<double> vals;
    // Cell nodes are indices into P.disc (the whole body, or a distributed problem's share, which
    // holds every node of an owned particle's cells: they lie within sqrt(D) dx <= 2 horizons).
    auto gid = [&](int node) { return P.distributed ? P.globalId[node] : static_cast<long long>(node); };
    for (long long p : ev.ownedParticles()) {
      for (int c = 0; c < D; ++c) row[c].clear();
      const int ip = P.index(p);
      const long long i = ijk[ip][0], j = ijk[ip][1], k = ijk[ip][2];
      for (int cell = 0; cell < nn; ++cell) {  // the cells having p as a corner
        const long long c0[3] = {i - (cell & 1), D > 1 ? j - ((cell >> 1) & 1) : 0, D > 2 ? k - ((cell >> 2) & 1) : 0};
        int nodes[8];
        bool whole = true;
        for (int a = 0; a < nn && whole; ++a) {
          nodes[a] = at(c0[0] + (a & 1), c0[1] + ((a >> 1) & 1), c0[2] + ((a >> 2) & 1));
          whole = nodes[a] >= 0;
        }
        if (!whole) continue;
        double scale = 1.0;  // a variable modulus: the mean of the element's nodes
        if (!P.modulusScale.empty()) {
          scale = 0;
          for (int a = 0; a < nn; ++a) scale += P.modulusScale[nodes[a]] / nn;
        }
        const int me = static_cast<int>(std::find(nodes, nodes + nn, ip) - nodes);
        Eigen::MatrixXd cellKe;
        if (!blockOf.empty()) {  // blocks: the mean of the corners' block stiffnesses (times their scales)
          cellKe = Eigen::MatrixXd::Zero(Ke.rows(), Ke.cols());
          for (int a = 0; a < nn; ++a)
            cellKe += (P.modulusScale.empty() ? 1.0 : P.modulusScale[nodes[a]]) / nn * blockKe[blockOf[nodes[a]]];
          scale = 1.0;
        }
        const Eigen::MatrixXd& K = blockOf.empty() ? Ke : cellKe;
        for (int c = 0; c < D; ++c) {
          if (ev.freeDof(p, c) < 0) continue;
          for (int a = 0; a < nn; ++a)
            for (int e = 0; e < D; ++e)
              if (!((P.fixedMask[nodes[a]] >> e) & 1u))  // prescribed columns eliminated (a node need not be local)
                row[c][static_cast<GO>(gid(nodes[a])) * D + e] += scale * K(me * D + c, a * D + e);
        }
      }
      for (int c = 0; c < D; ++c) {
        const GO g = static_cast<GO>(p) * D + c;
        cols.clear();
        vals.clear();
        if (ev.freeDof(p, c) < 0 || row[c].empty()) {  // prescribed, or in no whole cell
          cols.push_back(g);
          vals.push_back(diag[c]);
        } else {
          for (const auto& [cg, v] : row[c]) {
            cols.push_back(cg);
            vals.push_back(v);
          }
        }
        M->insertGlobalValues(g, static_cast<LO>(cols.size()), vals.data(), cols.data());
      }
    }
    M->fillComplete(allMap, allMap);
    return M;
  }

  RCP<const PeridynamicEvaluator> ev_;
  AuxiliaryOperator op_;
};

// ---------------------------------------------------------------------------------------------
// Short horizon

class ShortHorizonSource final : public AuxiliarySource {
 public:
  ShortHorizonSource(const RCP<const PeridynamicEvaluator>& ev, double factor) : ev_(ev.create_weak()), factor_(factor) {
    op_ = allDofLayout(*ev_, allMap_);
    rebuild(0);
  }
  const AuxiliaryOperator& current() override {
    long long mine = static_cast<long long>(ev_->ownedBrokenBonds().size()), broken = 0;
    Teuchos::reduceAll(*ev_->comm(), Teuchos::REDUCE_SUM, mine, Teuchos::outArg(broken));
    broken += static_cast<long long>(ev_->detachedParticles().size());
    if (broken != damage_) rebuild(broken);
    return op_;
  }
  std::string description() const override {
    std::ostringstream s;
    s << "peridynamic Jacobian at horizon " << factor_ << " dx, " << op_.matrix->getGlobalNumRows() << " rows";
    return s.str();
  }

 private:
  /// The auxiliary evaluator with the body's damage, its Jacobian at the unloaded state, copied
  /// onto the all-DOF map.
  void rebuild(long long damage) {
    const PeridynamicEvaluator& ev = *ev_;
    auto P = std::make_shared<ProblemSpec>(ev.problem());
    if (P->blocks.empty()) {
      P->stab = ev.problem().stabilizationSpec();  // the body's micromodulus, not the short horizon's
    } else {
      for (BlockSpec& blk : P->blocks) blk.C = ev.problem().stabilizationSpec(blk).C;  // each block's, likewise
    }
    P->disc.horizon = factor_ * P->disc.dx;
    if (!P->disc.familyOffset.empty()) buildFamilies(P->disc);  // else the evaluator finds its own
    auto aux = rcp(new PeridynamicEvaluator(ev.comm(), P));
    if (!aux->ownedFreeMap()->isSameAs(*ev.ownedFreeMap()))
      throw std::logic_error("the short-horizon auxiliary problem has another free-DOF map");
    if (damage > 0) {
      aux->restoreDamage(allBrokenBonds(), ev.detachedParticles(), ev.ownedFrozenDofs());
    }
    auto x0 = Thyra::createMember(aux->get_x_space());
    Thyra::assign(x0.ptr(), 0.0);
    if (damage > 0) aux->breakBonds(*x0);  // detaches what the shorter families leave singular
    aux->setLoadFactor(0.0);
    auto A = aux->assembledJacobian(*x0);
    op_.matrix = toAllDofs(*A);
    ++op_.version;
    damage_ = damage;
  }

  /// Every rank's broken bonds, on every rank (restoreDamage takes the global list).
  std::vector<std::pair<long long, long long>> allBrokenBonds() const {
    const auto mine = ev_->ownedBrokenBonds();
    const auto& comm = *ev_->comm();
    const int np = comm.getSize();
    std::vector<long long> flat;
    for (auto [a, b] : mine) {
      flat.push_back(a);
      flat.push_back(b);
    }
    long long count = static_cast<long long>(flat.size()), most = 0;
    Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, count, Teuchos::outArg(most));
    flat.resize(most, -1);
    std::vector<long long> gathered(static_cast<size_t>(most) * np);
    if (most > 0) Teuchos::gatherAll(comm, static_cast<int>(most), flat.data(), static_cast<int>(gathered.size()), gathered.data());
    std::vector<std::pair<long long, long long>> all;
    for (size_t k = 0; k + 1 < gathered.size(); k += 2)
      if (gathered[k] >= 0) all.emplace_back(gathered[k], gathered[k + 1]);
    return all;
  }

  /// A (free-DOF rows and columns) on the all-DOF map: free rows keep their entries, prescribed
  /// DOFs get a unit row scaled by the mean diagonal of their component.
  RCP<const TCrsMatrix> toAllDofs(const TCrsMatrix& A) const {
    const int D = op_.blockSize;
    const LO nAll = static_cast<LO>(allMap_->getNodeNumElements());
    // the all-DOF gid of every free DOF A's columns reach: owned free gid -> all gid, imported
    TVector allGid(A.getDomainMap());
    {
      auto g = allGid.getDataNonConst();
      for (size_t k = 0; k < op_.freeToAll.size(); ++k)
        g[k] = static_cast<double>(allMap_->getGlobalElement(op_.freeToAll[k]));  // exact below 2^53
    }
    TVector colGid(A.getColMap());
    colGid.doImport(allGid, Tpetra::Import<LO, GO, Node>(A.getDomainMap(), A.getColMap()), Tpetra::INSERT);
    // mean diagonal per component over the free DOFs (global)
    TVector d(A.getRowMap());
    A.getLocalDiagCopy(d);
    std::vector<double> sum(2 * D, 0.0), gsum(2 * D);
    {
      auto dd = d.getData();
      for (size_t k = 0; k < op_.freeToAll.size(); ++k) {
        sum[op_.freeToAll[k] % D] += std::abs(dd[k]);
        sum[D + op_.freeToAll[k] % D] += 1;
      }
    }
    Teuchos::reduceAll(*ev_->comm(), Teuchos::REDUCE_SUM, 2 * D, sum.data(), gsum.data());
    std::vector<LO> allToFree(nAll, -1);
    for (size_t k = 0; k < op_.freeToAll.size(); ++k) allToFree[op_.freeToAll[k]] = static_cast<LO>(k);
    auto cg = colGid.getData();
    auto M = rcp(new TCrsMatrix(allMap_, static_cast<size_t>(A.getNodeMaxNumRowEntries())));
    std::vector<GO> cols;
    std::vector<double> vals;
    for (LO r = 0; r < nAll; ++r) {
      const GO g = allMap_->getGlobalElement(r);
      const LO k = allToFree[r];
      cols.clear();
      vals.clear();
      if (k < 0) {
        const int c = static_cast<int>(g % D);
        cols.push_back(g);
        vals.push_back(gsum[D + c] > 0 ? gsum[c] / gsum[D + c] : 1.0);
      } else {
        TCrsMatrix::local_inds_host_view_type ind;
        TCrsMatrix::values_host_view_type val;
        A.getLocalRowView(k, ind, val);
        for (size_t q = 0; q < ind.extent(0); ++q) {
          cols.push_back(static_cast<GO>(cg[ind(q)]));
          vals.push_back(val(q));
        }
      }
      M->insertGlobalValues(g, static_cast<LO>(cols.size()), vals.data(), cols.data());
    }
    M->fillComplete(allMap_, allMap_);
    return M;
  }

  RCP<const PeridynamicEvaluator> ev_;
  double factor_;
  RCP<const TMap> allMap_;
  AuxiliaryOperator op_;
  long long damage_ = -1;
};

}  // namespace

bool onLattice(const Discretization& d) {
  if (d.X.empty() || !(d.dx > 0)) return false;
  const Eigen::Vector3d lo = lowestCorner(d);
  std::unordered_map<long long, int> seen;
  seen.reserve(d.X.size());
  std::array<long long, 3> n{{1, 1, 1}};
  for (const auto& X : d.X)
    for (int a = 0; a < d.dim; ++a) n[a] = std::max(n[a], std::llround((X[a] - lo[a]) / d.dx) + 1);
  for (const auto& X : d.X) {
    long long idx[3] = {0, 0, 0};
    for (int a = 0; a < d.dim; ++a) {
      const double s = (X[a] - lo[a]) / d.dx;
      idx[a] = std::llround(s);
      if (std::abs(s - static_cast<double>(idx[a])) > 1e-6) return false;
    }
    if (!seen.emplace((idx[2] * n[1] + idx[1]) * n[0] + idx[0], 1).second) return false;
  }
  return true;
}

std::shared_ptr<AuxiliarySource> makeAuxiliarySource(Teuchos::RCP<const PeridynamicEvaluator> evaluator,
                                                     const Teuchos::ParameterList& twoStage) {
  const ProblemSpec& P = evaluator->problem();
  const std::string kind =
      twoStage.isType<std::string>("Auxiliary Operator") ? twoStage.get<std::string>("Auxiliary Operator") : "Auto";
  bool lattice = onLattice(P.disc);
  if (P.distributed) {  // every rank's share must be (the ranks then agree on the operator)
    int mine = lattice ? 1 : 0, all = 0;
    Teuchos::reduceAll(*evaluator->comm(), Teuchos::REDUCE_MIN, mine, Teuchos::outArg(all));
    lattice = all != 0;
  }
  if (kind == "Lattice FEM" || (kind == "Auto" && lattice && !P.damage)) {
    if (!lattice)
      throw std::invalid_argument(
          "'Two-Stage/Auxiliary Operator' = Lattice FEM needs the particles on a lattice of spacing dx; these are not "
          "(use Short Horizon or Auto)");
    return std::make_shared<LatticeFemSource>(evaluator);
  }
  if (kind != "Short Horizon" && kind != "Auto")
    throw std::invalid_argument("'Two-Stage/Auxiliary Operator' = '" + kind +
                                "' is not one of Auto, Lattice FEM, Short Horizon");
  double factor = twoStage.isType<double>("Auxiliary Horizon Factor") ? twoStage.get<double>("Auxiliary Horizon Factor") : 0.0;
  if (factor == 0.0) factor = lattice ? 1.015 : 1.6;
  if (!(factor >= 1.0) || !std::isfinite(factor))
    throw std::invalid_argument("'Two-Stage/Auxiliary Horizon Factor' must be at least 1 (or 0 for the default)");
  factor = std::min(factor, P.disc.horizon / P.disc.dx);  // at most the body's own horizon
  return std::make_shared<ShortHorizonSource>(evaluator, factor);
}

}  // namespace perinox
