// Preconditioner benchmark for issue 19: Krylov iterations, set-up and solve cost of candidate
// preconditioners for GMRES on the assembled Jacobian of a scene (default: the tension block), as
// the particle count grows, with the cost of one residual evaluation measured in the same run so
// set-up + solve can be expressed in residual evaluations. Prints one row per (size, candidate)
// and appends it to a CSV file. Asserts nothing (timings on a shared machine are noisy; they go
// into docs/performance.md, not into tests).
//
//   bench_preconditioners [--scene xml/tension_block.xml] [--set Sublist/Key=value]...
//       --sizes 80x40 160x80 ... --candidates NAME|FILE.xml ... [--csv out.csv]
//       [--state affine|zero] [--tol 1e-10] [--restart 200] [--max-iterations 3000]
//       [--time-limit 600] [--operator assembled|matrix-free] [--tag TEXT] [--verbose] [--list]
//
// The linear system: J = df/dx and b = -f at load factor 1 and the state chosen by --state:
// "affine" (default) is the scene's analytic reference displacement (Reference/Type = Affine) on
// the free DOFs, within discretisation error of the converged state, so J is the tangent a late
// Newton iteration sees; "zero" is x = 0 (prescribed DOFs at their full values), the first Newton
// iteration of a one-step solve without a predictor (the full prescribed displacement as a jump
// between the loaded layers and the body); "predictor" is J at x = 0 and load factor 0 with
// b = -df/dlambda, the tangent-predictor solve that starts a perinox run. GMRES (Belos pseudo-block GMRES, right
// preconditioning, x0 = 0) runs to |b - J x| <= tol |b|; the true residual is checked afterwards.
//
// A candidate is a parameter list (built in: --list; or an XML file, named by its file name):
//   Matrix            Jacobian | Neighbours | Auxiliary | Q1     the matrix the preconditioner is built from
//   Auxiliary Horizon Factor  (Auxiliary) delta / dx of the auxiliary peridynamic problem (1.015)
//   DOF Map           Free | All    All: every DOF of the owned particles, prescribed ones as
//                                   decoupled diagonal rows, so the block size is constant (dim)
//   Preconditioner    Ifpack2 | MueLu | FROSch | None
//   Ifpack2 Type      (Ifpack2) e.g. RILUK, RELAXATION
//   Parameters        sublist handed to Ifpack2, MueLu or FROSch as it is
//   Fine Smoother     optional sublist {Type (an Ifpack2 type), Parameters}: a smoother on the
//                     assembled J around the preconditioner (two-stage: S, V, S; the library's twoStageOperator)
//   Build At          State (default) | Reference: the preconditioner's matrix at the unloaded
//                     state (x = 0, load factor 0), as one kept from the start of a run would be
//   Overlap           (FROSch) overlap in graph layers
// MueLu gets the rigid-body modes (zero on prescribed DOFs) as "Nullspace" and the particle
// positions as "Coordinates" (user data); FROSch gets the same through initialize().
// All Trilinos solver headers stay in this translation unit.
#include <BelosLinearProblem.hpp>
#include <BelosPseudoBlockGmresSolMgr.hpp>
#include <BelosTpetraAdapter.hpp>
#include <Ifpack2_Factory.hpp>
#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultComm.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>

#include <FROSch_Tools_def.hpp>
#include <FROSch_TwoLevelPreconditioner_def.hpp>
#include <Xpetra_CrsMatrixWrap.hpp>
#include <Xpetra_MapFactory.hpp>
#include <Xpetra_TpetraCrsMatrix.hpp>
#include <Xpetra_TpetraMultiVector.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/Scene.hpp"
#include "perinox/solver/AuxiliaryOperators.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"

using namespace perinox;

namespace {

using Node = TMap::node_type;
using MV = Tpetra::MultiVector<double, LO, GO, Node>;
using OP = Tpetra::Operator<double, LO, GO, Node>;
using RowMatrix = Tpetra::RowMatrix<double, LO, GO, Node>;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;
using Clock = std::chrono::steady_clock;
using Teuchos::RCP;
using Teuchos::rcp;

double seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

struct TimeLimit : std::runtime_error {
  TimeLimit() : std::runtime_error("time limit") {}
};

/// Wraps the preconditioner: counts applications and stops the solve (on every rank together)
/// once the time limit has passed.
class TimedOperator final : public OP {
 public:
  TimedOperator(RCP<const OP> inner, Clock::time_point deadline, RCP<const Teuchos::Comm<int>> comm)
      : inner_(inner), deadline_(deadline), comm_(comm) {}
  RCP<const TMap> getDomainMap() const override { return inner_->getDomainMap(); }
  RCP<const TMap> getRangeMap() const override { return inner_->getRangeMap(); }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    int late = Clock::now() > deadline_ ? 1 : 0, anyLate = 0;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, late, Teuchos::outArg(anyLate));
    if (anyLate) throw TimeLimit();
    ++applies;
    inner_->apply(X, Y, mode, alpha, beta);
  }
  mutable long applies = 0;

 private:
  RCP<const OP> inner_;
  Clock::time_point deadline_;
  RCP<const Teuchos::Comm<int>> comm_;
};

// The free-DOF restriction and the two-stage composition are the library's
// (perinox/solver/TwoStagePreconditioner.hpp: freeRestriction, twoStageOperator), so the study
// measures the operator the scalable preset applies.

/// FROSch's two-level Schwarz preconditioner as a Tpetra operator.
class FroschOperator final : public OP {
 public:
  using Prec = FROSch::TwoLevelPreconditioner<double, LO, GO, Node>;
  FroschOperator(RCP<Prec> p, RCP<const TMap> map) : p_(p), map_(map) {}
  RCP<const TMap> getDomainMap() const override { return map_; }
  RCP<const TMap> getRangeMap() const override { return map_; }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    Xpetra::TpetraMultiVector<double, LO, GO, Node> x(Teuchos::rcp_const_cast<MV>(Teuchos::rcpFromRef(X)));
    Xpetra::TpetraMultiVector<double, LO, GO, Node> y(Teuchos::rcpFromRef(Y));
    p_->apply(x, y, mode, alpha, beta);
  }

 private:
  RCP<Prec> p_;
  RCP<const TMap> map_;
};

// ---------------------------------------------------------------------------------------------
// The problem at one size

struct Problem {
  Scene scene;
  RCP<PeridynamicEvaluator> ev;
  RCP<Thyra::VectorBase<double>> x, b;  // state and right-hand side -f(x)
  RCP<TCrsMatrix> J;
  // All-DOF map: every DOF of the owned particles, gid = particle * dim + component.
  RCP<const TMap> allMap, nodeMap;      // nodeMap: owned particles (gid = particle id)
  std::vector<LO> freeToAll;            // owned free lid -> all-DOF lid
  double tResidual = 0, tMatvec = 0, tAssemble = 0, tJvMf = 0;
  long long realParticles = 0;
  // The matrix-free analytic product J v (a second evaluator in matrix-free mode, at x).
  RCP<PeridynamicEvaluator> mfEv;
  RCP<Thyra::LinearOpBase<double>> mfW;
  RCP<const OP> Jmf;
  bool matrixFree = false;              // GMRES runs on Jmf instead of the assembled J
  struct Aux {
    RCP<PeridynamicEvaluator> ev;
    RCP<Thyra::VectorBase<double>> x;
    double tBuild = 0;
  };
  mutable std::map<double, Aux> aux;    // auxiliary problems by horizon factor
  mutable bool nbrBuilt = false;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void residual(const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& f) {
  auto in = ev.createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto out = ev.createOutArgs();
  out.set_f(Teuchos::rcpFromRef(f));
  ev.evalModel(in, out);
}

/// x on the free DOFs of ev from the scene's affine reference (or zero).
void setState(const Scene& scene, const PeridynamicEvaluator& ev, const std::string& state, Thyra::VectorBase<double>& x) {
  Thyra::assign(Teuchos::ptrFromRef(x), 0.0);
  if (state == "zero" || state == "predictor") return;
  if (state != "affine") throw std::invalid_argument("--state must be affine, zero or predictor");
  if (scene.reference.type == "None")
    throw std::invalid_argument("--state affine needs the scene's Reference (an analytic displacement)");
  std::vector<std::pair<long long, double>> values;
  const ProblemSpec& P = ev.problem();
  for (long long p : ev.ownedParticles())
    for (int c = 0; c < P.dim(); ++c) {
      if (ev.freeDof(p, c) >= 0) values.emplace_back(p * P.dim() + c, scene.reference.displacement(P.disc.X[p], c));
    }
  ev.setOwnedDofValues(x, values);
}

/// The all-DOF copy of a free-DOF matrix A (rows and columns of the free DOFs, the same map as
/// ev's): free rows keep their entries, prescribed DOFs get a diagonal row (value diag[c], c the
/// component), so every particle has dim rows.
RCP<TCrsMatrix> toAllDofs(const Problem& pb, const TCrsMatrix& A, const std::vector<double>& diag) {
  const PeridynamicEvaluator& ev = *pb.ev;
  const int D = ev.problem().dim();
  const LO nOwnedParticles = static_cast<LO>(ev.ownedParticles().size());
  const LO nAll = nOwnedParticles * D;
  // Column map: the owned all-DOFs in row order, then the remote columns of A.
  auto Acol = A.getColMap();
  auto Adom = A.getDomainMap();
  std::vector<GO> colGids;
  colGids.reserve(nAll + Acol->getNodeNumElements());
  for (LO r = 0; r < nAll; ++r) colGids.push_back(pb.allMap->getGlobalElement(r));
  // The all-DOF gid of every column, from its owner (exact as doubles below 2^53).
  TVector names(Adom), colNames(Acol);
  {
    auto nd = names.getDataNonConst();
    for (std::size_t k = 0; k < pb.freeToAll.size(); ++k) nd[k] = static_cast<double>(pb.allMap->getGlobalElement(pb.freeToAll[k]));
  }
  colNames.doImport(names, Tpetra::Import<LO, GO>(Adom, Acol), Tpetra::INSERT);
  const auto cn = colNames.getData();
  std::vector<LO> colOf(Acol->getNodeNumElements());
  for (LO j = 0; j < static_cast<LO>(Acol->getNodeNumElements()); ++j) {
    const GO g = Acol->getGlobalElement(j);
    const LO own = Adom->getLocalElement(g);
    if (own >= 0) {
      colOf[j] = pb.freeToAll[own];
    } else {
      colOf[j] = static_cast<LO>(colGids.size());
      colGids.push_back(static_cast<GO>(cn[j]));
    }
  }
  auto colMap = rcp(new TMap(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(), colGids.data(),
                             colGids.size(), 0, pb.allMap->getComm()));
  // all lid -> free lid (-1 prescribed)
  std::vector<LO> allToFree(nAll, -1);
  for (size_t k = 0; k < pb.freeToAll.size(); ++k) allToFree[pb.freeToAll[k]] = static_cast<LO>(k);
  Teuchos::ArrayRCP<size_t> rowPtr(nAll + 1);
  rowPtr[0] = 0;
  for (LO r = 0; r < nAll; ++r) {
    const LO k = allToFree[r];
    rowPtr[r + 1] = rowPtr[r] + (k >= 0 ? A.getNumEntriesInLocalRow(k) : 1);
  }
  Teuchos::ArrayRCP<LO> cols(rowPtr[nAll]);
  Teuchos::ArrayRCP<double> vals(rowPtr[nAll]);
  std::vector<std::pair<LO, double>> row;
  for (LO r = 0; r < nAll; ++r) {
    const LO k = allToFree[r];
    size_t at = rowPtr[r];
    if (k < 0) {
      cols[at] = r;
      vals[at] = diag[r % D];
      continue;
    }
    TCrsMatrix::local_inds_host_view_type ind;
    TCrsMatrix::values_host_view_type val;
    A.getLocalRowView(k, ind, val);
    row.clear();
    for (size_t q = 0; q < ind.extent(0); ++q) row.emplace_back(colOf[ind(q)], val(q));
    std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [c, v] : row) {
      cols[at] = c;
      vals[at++] = v;
    }
  }
  auto M = rcp(new TCrsMatrix(pb.allMap, colMap, rowPtr, cols, vals));
  M->fillComplete(pb.allMap, pb.allMap);
  return M;
}

/// Mean diagonal of A per component over the free DOFs (global), for the prescribed rows.
std::vector<double> meanDiagonal(const Problem& pb, const TCrsMatrix& A) {
  const PeridynamicEvaluator& ev = *pb.ev;
  const int D = ev.problem().dim();
  TVector d(A.getRowMap());
  A.getLocalDiagCopy(d);
  auto dd = d.getData();
  std::vector<double> sum(D, 0.0), cnt(D, 0.0), gsum(D), gcnt(D);
  for (size_t k = 0; k < pb.freeToAll.size(); ++k) {
    sum[pb.freeToAll[k] % D] += std::abs(dd[k]);
    cnt[pb.freeToAll[k] % D] += 1;
  }
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, D, sum.data(), gsum.data());
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, D, cnt.data(), gcnt.data());
  for (int c = 0; c < D; ++c) gsum[c] = gcnt[c] > 0 ? gsum[c] / gcnt[c] : 1.0;
  return gsum;
}

/// Rigid-body modes on a map whose local entries follow the owned particles' DOFs (all DOFs, or
/// the free ones only); prescribed DOFs get zero on the all-DOF map.
RCP<MV> rigidBodyModes(const Problem& pb, bool allDofs, bool zeroPrescribed) {
  const PeridynamicEvaluator& ev = *pb.ev;
  const ProblemSpec& P = ev.problem();
  const int D = P.dim();
  const int nModes = rigidModeCount(D);
  auto B = rcp(new MV(allDofs ? pb.allMap : ev.ownedFreeMap(), nModes));
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& X : P.disc.X) c += X;
  c /= static_cast<double>(P.disc.size());
  const double L = P.disc.horizon;
  for (int m = 0; m < nModes; ++m) {
    auto col = B->getDataNonConst(m);
    LO k = 0;
    for (long long p : ev.ownedParticles()) {
      const Eigen::Vector3d r = (P.disc.X[p] - c) / L;
      for (int a = 0; a < D; ++a) {
        const bool fixed = ev.freeDof(p, a) < 0;
        if (fixed && !allDofs) continue;
        col[k++] = fixed && zeroPrescribed ? 0.0 : rigidModeValue(m, a, D, r);
      }
    }
  }
  return B;
}

/// Particle coordinates: on the node map (all-DOF map: one node per particle) or, for the free
/// map with one equation per node, one row per free DOF (the DOF's particle's position).
RCP<MV> coordinates(const Problem& pb, bool perFreeDof) {
  const PeridynamicEvaluator& ev = *pb.ev;
  const ProblemSpec& P = ev.problem();
  const int D = P.dim();
  auto C = rcp(new MV(perFreeDof ? ev.ownedFreeMap() : pb.nodeMap, D));
  for (int a = 0; a < D; ++a) {
    auto col = C->getDataNonConst(a);
    LO k = 0;
    for (long long p : ev.ownedParticles()) {
      if (!perFreeDof) {
        col[k++] = P.disc.X[p][a];
        continue;
      }
      for (int c = 0; c < D; ++c)
        if (ev.freeDof(p, c) >= 0) col[k++] = P.disc.X[p][a];
    }
  }
  return C;
}

// ---------------------------------------------------------------------------------------------
// Q1 (2D) / Q1 hexahedral (3D) finite-element stiffness on the lattice of the particles

/// The Q1 stiffness of the lattice through all particles (real and fictitious), on the all-DOF
/// map, with prescribed DOFs eliminated (their rows and columns replaced by a unit diagonal
/// scaled by diag).
RCP<TCrsMatrix> q1Matrix(const Problem& pb, const std::vector<double>& diag) {
  const PeridynamicEvaluator& ev = *pb.ev;
  const ProblemSpec& P = ev.problem();
  const int D = P.dim();
  const double h = P.disc.dx;
  Eigen::Vector3d lo = P.disc.X[0];
  for (const auto& X : P.disc.X) lo = lo.cwiseMin(X);
  std::array<long long, 3> n{{1, 1, 1}};
  std::vector<std::array<long long, 3>> ijk(P.disc.size());
  for (int p = 0; p < P.disc.size(); ++p)
    for (int d = 0; d < D; ++d) {
      ijk[p][d] = std::llround((P.disc.X[p][d] - lo[d]) / h);
      n[d] = std::max(n[d], ijk[p][d] + 1);
    }
  std::vector<int> grid(n[0] * n[1] * n[2], -1);
  auto at = [&](long long i, long long j, long long k) -> int {
    if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return -1;
    return grid[(k * n[1] + j) * n[0] + i];
  };
  for (int p = 0; p < P.disc.size(); ++p) {
    long long i = ijk[p][0], j = D > 1 ? ijk[p][1] : 0, k = D > 2 ? ijk[p][2] : 0;
    grid[(k * n[1] + j) * n[0] + i] = p;
  }
  const Eigen::MatrixXd Ke = latticeElementStiffness(D, h, P.material, P.disc.thickness);
  const int nn = 1 << D;
  auto M = rcp(new TCrsMatrix(pb.allMap, D == 2 ? 18 : 81));
  std::map<GO, double> row[3];
  for (long long p : ev.ownedParticles()) {
    for (int c = 0; c < D; ++c) row[c].clear();
    const long long i = ijk[p][0], j = D > 1 ? ijk[p][1] : 0, k = D > 2 ? ijk[p][2] : 0;
    // the cells having p as a corner: lower corner at (i - a0, j - a1, k - a2)
    for (int cell = 0; cell < nn; ++cell) {
      long long c0[3] = {i - (cell & 1), D > 1 ? j - ((cell >> 1) & 1) : 0, D > 2 ? k - ((cell >> 2) & 1) : 0};
      int nodes[8];
      bool ok = true;
      for (int a = 0; a < nn && ok; ++a) {
        nodes[a] = at(c0[0] + (a & 1), c0[1] + ((a >> 1) & 1), c0[2] + ((a >> 2) & 1));
        ok = nodes[a] >= 0;
      }
      if (!ok) continue;
      int me = -1;
      for (int a = 0; a < nn; ++a)
        if (nodes[a] == p) me = a;
      for (int c = 0; c < D; ++c) {
        if (ev.freeDof(p, c) < 0) continue;
        for (int a = 0; a < nn; ++a)
          for (int e = 0; e < D; ++e) {
            if (P.isFixed(nodes[a], e)) continue;  // eliminated (a node need not be local)
            row[c][static_cast<GO>(nodes[a]) * D + e] += Ke(me * D + c, a * D + e);
          }
      }
    }
    for (int c = 0; c < D; ++c) {
      const GO g = static_cast<GO>(p) * D + c;
      std::vector<GO> cols;
      std::vector<double> vals;
      if (ev.freeDof(p, c) < 0) {
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
  M->fillComplete(pb.allMap, pb.allMap);
  return M;
}

// ---------------------------------------------------------------------------------------------
// Candidates

Teuchos::ParameterList mueluBase(int dim, bool allDofs) {
  Teuchos::ParameterList p;
  p.set("verbosity", "none");
  p.set("multigrid algorithm", "sa");
  p.set("number of equations", allDofs ? dim : 1);
  p.set("max levels", 10);
  p.set("coarse: max size", 1000);
  p.set("coarse: type", "KLU2");
  p.set("aggregation: type", "uncoupled");
  p.set("smoother: type", "CHEBYSHEV");
  Teuchos::ParameterList sp;
  sp.set("chebyshev: degree", 3);
  sp.set("chebyshev: ratio eigenvalue", 7.0);
  sp.set("chebyshev: zero starting solution", true);
  p.set("smoother: params", sp);
  return p;
}

/// The candidates collected so far, with the ways to add one.
struct CandidateSet {
  int dim;
  std::map<std::string, Teuchos::ParameterList> c;

  /// Ifpack2 RILUK(fill) on the given matrix, free-DOF map.
  void ifpack(const std::string& name, const std::string& matrix, int fill) {
    Teuchos::ParameterList p;
    p.set("Matrix", matrix);
    p.set("DOF Map", "Free");
    p.set("Preconditioner", "Ifpack2");
    p.set("Ifpack2 Type", "RILUK");
    p.sublist("Parameters").set("fact: iluk level-of-fill", fill);
    c[name] = p;
  }
  /// MueLu (mueluBase) on the given matrix; returns its MueLu list to adjust.
  Teuchos::ParameterList& muelu(const std::string& name, const std::string& matrix, bool allDofs) {
    Teuchos::ParameterList p;
    p.set("Matrix", matrix);
    p.set("DOF Map", allDofs ? "All" : "Free");
    p.set("Preconditioner", "MueLu");
    p.set("Parameters", mueluBase(dim, allDofs));
    c[name] = p;
    return c[name].sublist("Parameters");
  }
  /// The candidate base with a smoother on J itself around its V-cycle.
  void fine(const std::string& base, const std::string& name, const std::string& type, int degree) {
    c[name] = c[base];
    auto& fs = c[name].sublist("Fine Smoother");
    fs.set("Type", type);
    if (type == "CHEBYSHEV") {
      fs.sublist("Parameters").set("chebyshev: degree", degree);
      fs.sublist("Parameters").set("chebyshev: ratio eigenvalue", 7.0);
      fs.sublist("Parameters").set("chebyshev: zero starting solution", true);
    } else if (type == "RELAXATION") {
      fs.sublist("Parameters").set("relaxation: type", "Symmetric Gauss-Seidel");
      fs.sublist("Parameters").set("relaxation: zero starting solution", true);
    } else {
      fs.sublist("Parameters").set("fact: iluk level-of-fill", 0);
    }
  }
  /// The candidate base built once at the reference state (name base@ref).
  void atReference(const std::string& base) {
    c[base + "@ref"] = c[base];
    c[base + "@ref"].set("Build At", "Reference");
  }
};

/// One symmetric Gauss-Seidel sweep as MueLu's level smoother.
void sgsSmoother(Teuchos::ParameterList& m) {
  m.set("smoother: type", "RELAXATION");
  Teuchos::ParameterList sp;
  sp.set("relaxation: type", "Symmetric Gauss-Seidel");
  sp.set("relaxation: sweeps", 1);
  m.set("smoother: params", sp);
}

/// (a) MueLu on the full Jacobian: DOF maps, drop schemes, aggregates and smoothers.
void addJacobianMueluCandidates(CandidateSet& s) {
  const int dim = s.dim;
  {  // what the issue tried: the free-DOF map with 'number of equations' = dim (invalid block size)
    auto& m = s.muelu("muelu-J-free-numeq", "Jacobian", false);
    m.set("number of equations", dim);
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.02);
    m.set("coarse: max size", 300);
  }
  {  // free map, one equation per node (scalar aggregation of the DOFs), rigid-body modes
    auto& m = s.muelu("muelu-J-free-scalar", "Jacobian", false);
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.02);
  }
  {  // all-DOF map, no dropping
    auto& m = s.muelu("muelu-J-all", "Jacobian", true);
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.0);
  }
  {  // all-DOF map, distance-Laplacian dropping (coordinates) to the nearest neighbours
    auto& m = s.muelu("muelu-J-dl", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.05);
    m.set("aggregation: min agg size", 4);
    m.set("aggregation: max agg size", 16);
    m.set("sa: use filtered matrix", true);
    m.set("filtered matrix: use lumping", true);
  }
  {  // the same with a weaker drop (second neighbours kept)
    auto& m = s.muelu("muelu-J-dl02", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.02);
    m.set("sa: use filtered matrix", true);
    m.set("filtered matrix: use lumping", true);
  }
  {  // muelu-J-dl02 without lumping the dropped couplings onto the diagonal of the filtered matrix
    auto& m = s.muelu("muelu-J-dl02-nolump", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.02);
    m.set("sa: use filtered matrix", true);
    m.set("filtered matrix: use lumping", false);
  }
  {  // muelu-J-dl02 with Chebyshev degree 2 (each degree costs one product with J)
    auto& m = s.muelu("muelu-J-dl02-cheb2", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.02);
    m.set("sa: use filtered matrix", true);
    m.sublist("smoother: params").set("chebyshev: degree", 2);
  }
  {  // muelu-J-dl02 with larger aggregates
    auto& m = s.muelu("muelu-J-dl02-agg", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.02);
    m.set("aggregation: min agg size", 9);
    m.set("aggregation: max agg size", 30);
    m.set("sa: use filtered matrix", true);
  }
  {  // the same as muelu-J-dl with symmetric Gauss-Seidel smoothing
    auto& m = s.muelu("muelu-J-dl-sgs", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.05);
    m.set("sa: use filtered matrix", true);
    sgsSmoother(m);
  }
  {  // the same with ILU(0) smoothing
    auto& m = s.muelu("muelu-J-dl-ilu", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.05);
    m.set("sa: use filtered matrix", true);
    m.set("smoother: type", "RILUK");
    Teuchos::ParameterList sp;
    sp.set("fact: iluk level-of-fill", 0);
    m.set("smoother: params", sp);
  }
  {  // the same with Chebyshev degree 5
    auto& m = s.muelu("muelu-J-dl-cheb5", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.05);
    m.set("sa: use filtered matrix", true);
    m.sublist("smoother: params").set("chebyshev: degree", 5);
  }
  {  // the same with Chebyshev degree 2
    auto& m = s.muelu("muelu-J-dl-cheb2", "Jacobian", true);
    m.set("aggregation: drop scheme", "distance laplacian");
    m.set("aggregation: drop tol", 0.05);
    m.set("sa: use filtered matrix", true);
    m.sublist("smoother: params").set("chebyshev: degree", 2);
  }
}

/// (b) MueLu on auxiliary local operators (the nearest-neighbour correspondence operator, Q1, the
/// direct-neighbour part of J), alone and with a smoother on J around the V-cycle.
void addAuxiliaryCandidates(CandidateSet& s) {
  for (const char* f : {"1.015", "1.5", "2.015"}) {
    auto& m = s.muelu(std::string("aux") + f, "Auxiliary", true);
    s.c[std::string("aux") + f].set("Auxiliary Horizon Factor", std::stod(f));
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.0);
  }
  {
    auto& m = s.muelu("aux1.015-sgs", "Auxiliary", true);
    s.c["aux1.015-sgs"].set("Auxiliary Horizon Factor", 1.015);
    sgsSmoother(m);
  }
  {
    auto& m = s.muelu("q1", "Q1", true);
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.0);
  }
  {
    auto& m = s.muelu("q1-sgs", "Q1", true);
    sgsSmoother(m);
  }
  {  // the direct-neighbour part of J (today's mf-muelu matrix), on the all-DOF map
    auto& m = s.muelu("nbr", "Neighbours", true);
    m.set("aggregation: drop scheme", "classical");
    m.set("aggregation: drop tol", 0.0);
  }
  s.fine("aux1.015", "aux1.015+cheb2", "CHEBYSHEV", 2);
  s.fine("aux1.015", "aux1.015+cheb3", "CHEBYSHEV", 3);
  s.fine("aux1.015", "aux1.015+sgs", "RELAXATION", 1);
  s.fine("aux1.015", "aux1.015+ilu0", "RILUK", 0);
  s.fine("aux1.5", "aux1.5+cheb2", "CHEBYSHEV", 2);
  s.fine("aux1.5", "aux1.5+sgs", "RELAXATION", 1);
  s.fine("q1", "q1+cheb2", "CHEBYSHEV", 2);
  s.fine("q1", "q1+sgs", "RELAXATION", 1);
}

/// (c) FROSch two-level Schwarz on the full Jacobian (all-DOF map), overlaps 1 and 2, GDSW and RGDSW.
void addFroschCandidates(CandidateSet& s) {
  for (int ov : {1, 2}) {
    for (const char* coarse : {"GDSW", "RGDSW"}) {
      Teuchos::ParameterList p;
      p.set("Matrix", "Jacobian");
      p.set("DOF Map", "All");
      p.set("Preconditioner", "FROSch");
      p.set("Overlap", ov);
      auto& f = p.sublist("Parameters");
      f.set("CoarseOperator Type", std::string(coarse) + "CoarseOperator");
      f.set("OverlappingOperator Type", "AlgebraicOverlappingOperator");
      f.set("Null Space Type", "Input");
      f.sublist("AlgebraicOverlappingOperator").sublist("Solver").set("SolverType", "Amesos2");
      f.sublist("AlgebraicOverlappingOperator").sublist("Solver").set("Solver", "Klu");
      auto& co = f.sublist(std::string(coarse) + "CoarseOperator");
      auto& b1 = co.sublist("Blocks").sublist("1");
      b1.set("Use For Coarse Space", true);
      b1.set("Rotations", true);
      co.sublist("ExtensionSolver").set("SolverType", "Amesos2");
      co.sublist("ExtensionSolver").set("Solver", "Klu");
      co.sublist("CoarseSolver").set("SolverType", "Amesos2");
      co.sublist("CoarseSolver").set("Solver", "Klu");
      co.sublist("Distribution").set("Type", "linear");
      co.sublist("Distribution").set("NumProcs", 1);
      s.c[std::string("frosch-") + (coarse[0] == 'G' ? "gdsw" : "rgdsw") + "-ov" + std::to_string(ov)] = p;
    }
  }
}

/// The built-in candidates, by name.
std::map<std::string, Teuchos::ParameterList> builtinCandidates(int dim) {
  CandidateSet s{dim, {}};
  s.ifpack("ilu0", "Jacobian", 0);
  s.ifpack("riluk1", "Jacobian", 1);
  addJacobianMueluCandidates(s);
  addAuxiliaryCandidates(s);
  addFroschCandidates(s);
  for (const char* base : {"aux1.015+cheb2", "muelu-J-dl02", "ilu0"}) s.atReference(base);
  Teuchos::ParameterList none;
  none.set("Matrix", "Jacobian");
  none.set("DOF Map", "Free");
  none.set("Preconditioner", "None");
  s.c["none"] = none;
  return s.c;
}

struct Result {
  std::string status = "converged";
  int iterations = -1;
  double trueResidual = NAN, tMatrix = 0, tSetup = 0, tSolve = 0, tOnce = 0, tFine = 0;  // tFine: part of tSetup
  long long precNnz = 0;
  int levels = 0;
  double complexity = NAN;
  std::string note;
};

/// Builds the problem at one lattice size.
Problem buildProblem(const RCP<const Teuchos::Comm<int>>& comm, const std::string& scenePath,
                     std::vector<std::string> sets, const std::string& size, const std::string& state,
                     const std::string& presetDir) {
  Problem pb;
  std::vector<long long> counts;
  {
    std::stringstream ss(size);
    std::string tok;
    while (std::getline(ss, tok, 'x')) counts.push_back(std::stoll(tok));
  }
  std::string arr = "{";
  pb.realParticles = 1;
  for (size_t k = 0; k < counts.size(); ++k) {
    arr += (k ? "," : "") + std::to_string(counts[k]);
    pb.realParticles *= counts[k];
  }
  sets.push_back("Discretization/Particles=" + arr + "}");
  pb.scene = loadScene(scenePath, sets, presetDir);
  pb.ev = rcp(new PeridynamicEvaluator(comm, pb.scene.problem));
  // "predictor": the first linear solve of a run with prescribed motion, the tangent predictor
  // J(0, 0) dx/dlambda = -df/dlambda (the linear tangent of the unloaded body)
  pb.ev->setLoadFactor(state == "predictor" ? 0.0 : 1.0);
  const PeridynamicEvaluator& ev = *pb.ev;
  const int D = ev.problem().dim();
  pb.x = Thyra::createMember(ev.get_x_space());
  pb.b = Thyra::createMember(ev.get_f_space());
  setState(pb.scene, ev, state, *pb.x);
  // the all-DOF and node maps
  std::vector<GO> all, nodes;
  for (long long p : ev.ownedParticles()) {
    nodes.push_back(p);
    for (int c = 0; c < D; ++c) all.push_back(p * D + c);
  }
  const auto inv = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  pb.allMap = rcp(new TMap(inv, all.data(), all.size(), 0, comm));
  pb.nodeMap = rcp(new TMap(inv, nodes.data(), nodes.size(), 0, comm));
  auto fm = ev.ownedFreeMap();
  pb.freeToAll.assign(fm->getNodeNumElements(), -1);
  const auto& owned = ev.ownedParticles();
  for (std::size_t l = 0; l < owned.size(); ++l)
    for (int c = 0; c < D; ++c)
      if (ev.freeDof(owned[l], c) >= 0) pb.freeToAll[fm->getLocalElement(ev.freeDof(owned[l], c))] = l * D + c;
  // costs: residual (median of 5 after a warm-up), assembly, mat-vec
  residual(ev, *pb.x, *pb.b);
  std::vector<double> t;
  for (int r = 0; r < 5; ++r) {
    comm->barrier();
    const auto a = Clock::now();
    residual(ev, *pb.x, *pb.b);
    comm->barrier();
    t.push_back(seconds(a));
  }
  pb.tResidual = median(t);
  if (state == "predictor") ev.loadDerivative(*pb.x, *pb.b);
  Thyra::scale(-1.0, pb.b.ptr());
  // the first assembly also builds the graph; the second is what a Newton iteration pays
  pb.J = ev.assembledJacobian(*pb.x);
  pb.J = Teuchos::null;  // one copy at a time (the graph stays with the evaluator)
  comm->barrier();
  auto a = Clock::now();
  pb.J = ev.assembledJacobian(*pb.x);
  comm->barrier();
  pb.tAssemble = seconds(a);
  MV y(pb.J->getRangeMap(), 1), v(pb.J->getDomainMap(), 1);
  v.randomize();
  t.clear();
  for (int r = 0; r < 6; ++r) {
    comm->barrier();
    a = Clock::now();
    pb.J->apply(v, y);
    comm->barrier();
    if (r) t.push_back(seconds(a));
  }
  pb.tMatvec = median(t);
  // the matrix-free product at the same state
  pb.mfEv = rcp(new PeridynamicEvaluator(comm, pb.scene.problem));
  pb.mfEv->setJacobian(JacobianMode::MatrixFree, PreconditionerMatrix::Neighbours, Teuchos::null);
  pb.mfEv->setLoadFactor(ev.loadFactor());
  pb.mfW = pb.mfEv->create_W_op();
  {
    auto xm = Thyra::createMember(pb.mfEv->get_x_space());
    TOE::getTpetraVector(xm)->assign(*TOE::getConstTpetraVector(pb.x));
    auto in = pb.mfEv->createInArgs();
    in.set_x(xm);
    auto out = pb.mfEv->createOutArgs();
    out.set_W_op(pb.mfW);
    pb.mfEv->evalModel(in, out);
  }
  pb.Jmf = TOE::getConstTpetraOperator(pb.mfW);
  t.clear();
  MV ymf(pb.J->getRangeMap(), 1);
  for (int r = 0; r < 6; ++r) {
    comm->barrier();
    a = Clock::now();
    pb.Jmf->apply(v, ymf);
    comm->barrier();
    if (r) t.push_back(seconds(a));
  }
  pb.tJvMf = median(t);
  ymf.update(-1.0, y, 1.0);
  std::vector<double> dn(1), yn(1);
  ymf.norm2(Teuchos::ArrayView<double>(dn));
  y.norm2(Teuchos::ArrayView<double>(yn));
  TEUCHOS_TEST_FOR_EXCEPTION(!(dn[0] <= 1e-8 * yn[0]), std::logic_error,
                             "the matrix-free product differs from the assembled one: " << dn[0] / yn[0]);
  return pb;
}

/// The auxiliary evaluator's Jacobian (same particles and fixedMask, families rebuilt with the
/// candidate's smaller horizon). The evaluator is built once per size: its construction and first
/// assembly are reported apart (res.tOnce), and t0 restarts after them.
RCP<TCrsMatrix> auxiliaryMatrix(const Problem& pb, Teuchos::ParameterList cand, bool atReference, Result& res,
                                Clock::time_point& t0) {
  const PeridynamicEvaluator& ev = *pb.ev;
  auto comm = ev.comm();
  // The auxiliary evaluator (same particles and fixedMask, families rebuilt with the smaller
  // horizon) is built once per size: its construction and first assembly are reported apart.
  const double factor = cand.get<double>("Auxiliary Horizon Factor", 1.015);
  auto& entry = pb.aux[factor];
  if (entry.ev.is_null()) {
    const auto tb = Clock::now();
    auto P = std::make_shared<ProblemSpec>(ev.problem());
    P->disc.horizon = factor * P->disc.dx;
    if (!P->disc.familyOffset.empty()) buildFamilies(P->disc);  // else the evaluator finds its own
    entry.ev = rcp(new PeridynamicEvaluator(comm, P));
    entry.ev->setLoadFactor(ev.loadFactor());
    TEUCHOS_TEST_FOR_EXCEPTION(!entry.ev->ownedFreeMap()->isSameAs(*ev.ownedFreeMap()), std::logic_error,
                               "the auxiliary problem has another free-DOF map");
    entry.x = Thyra::createMember(entry.ev->get_x_space());
    TOE::getTpetraVector(entry.x)->assign(*TOE::getConstTpetraVector(pb.x));
    entry.ev->assembledJacobian(*entry.x);
    comm->barrier();
    entry.tBuild = seconds(tb);
    t0 = Clock::now();
  }
  res.tOnce = entry.tBuild;
  if (atReference) {
    auto xr = entry.x->clone_v();
    Thyra::assign(xr.ptr(), 0.0);
    const double keep = entry.ev->loadFactor();
    entry.ev->setLoadFactor(0.0);
    auto A = entry.ev->assembledJacobian(*xr);
    entry.ev->setLoadFactor(keep);
    return A;
  }
  return entry.ev->assembledJacobian(*entry.x);
}

/// The preconditioner's matrix on the free map (free) and, for all-DOF candidates, on the all-DOF
/// map (all); res.tMatrix and res.precNnz.
struct PrecMatrices {
  RCP<TCrsMatrix> free, all;
};

PrecMatrices preconditionerMatrix(const Problem& pb, Teuchos::ParameterList cand, Result& res) {
  const PeridynamicEvaluator& ev = *pb.ev;
  auto comm = ev.comm();
  const std::string matrix = cand.get<std::string>("Matrix", "Jacobian");
  const bool allDofs = cand.get<std::string>("DOF Map", "Free") == "All";
  comm->barrier();
  auto t0 = Clock::now();
  PrecMatrices m;
  RCP<TCrsMatrix>& A = m.free;
  RCP<TCrsMatrix>& Aall = m.all;
  // "Build At = Reference": the preconditioner's matrix is taken at the unloaded state (x = 0,
  // load factor 0: the linear tangent) instead of the state of the system, as a preconditioner
  // kept from the start of a run would be (the fine smoother of a two-stage candidate still uses
  // the current J).
  const bool atReference = cand.get<std::string>("Build At", "State") == "Reference";
  RCP<Thyra::VectorBase<double>> x0;
  if (atReference) {
    x0 = pb.x->clone_v();
    Thyra::assign(x0.ptr(), 0.0);
  }
  if (matrix == "Jacobian" && !atReference) {
    A = pb.J;
  } else if (matrix == "Jacobian") {
    const double keep = pb.ev->loadFactor();
    pb.ev->setLoadFactor(0.0);
    A = ev.assembledJacobian(*x0);
    pb.ev->setLoadFactor(keep);
  } else if (matrix == "Neighbours") {
    // built once per size (graph), then timed as a Newton iteration would pay it
    if (!pb.nbrBuilt) {
      ev.assembledJacobian(*pb.x, true);
      pb.nbrBuilt = true;
      comm->barrier();
      t0 = Clock::now();
    }
    A = ev.assembledJacobian(*pb.x, true);
  } else if (matrix == "Auxiliary") {
    A = auxiliaryMatrix(pb, cand, atReference, res, t0);
  } else if (matrix == "Q1") {
    TEUCHOS_TEST_FOR_EXCEPTION(!allDofs, std::invalid_argument, "Matrix Q1 is built on the all-DOF map");
  } else {
    throw std::invalid_argument("unknown Matrix '" + matrix + "'");
  }
  if (allDofs) {
    const auto diag = meanDiagonal(pb, A.is_null() ? *pb.J : *A);
    Aall = matrix == "Q1" ? q1Matrix(pb, diag) : toAllDofs(pb, *A, diag);
  }
  comm->barrier();
  res.tMatrix = seconds(t0);
  res.precNnz = allDofs ? Aall->getGlobalNumEntries() : A->getGlobalNumEntries();

  return m;
}

/// The candidate's preconditioner for J on the free map, from its matrices; res.tSetup and the
/// hierarchy's figures.
RCP<const OP> buildPreconditioner(const Problem& pb, Teuchos::ParameterList cand, const PrecMatrices& m, Result& res, bool verbose) {
  const PeridynamicEvaluator& ev = *pb.ev;
  auto comm = ev.comm();
  const int D = ev.problem().dim();
  const bool allDofs = cand.get<std::string>("DOF Map", "Free") == "All";
  const std::string precType = cand.get<std::string>("Preconditioner", "None");
  Teuchos::ParameterList params = cand.isSublist("Parameters") ? cand.sublist("Parameters") : Teuchos::ParameterList();
  const RCP<TCrsMatrix>& A = m.free;
  const RCP<TCrsMatrix>& Aall = m.all;
  comm->barrier();
  auto t0 = Clock::now();
  RCP<const OP> M;
  if (precType == "Ifpack2") {
    TEUCHOS_TEST_FOR_EXCEPTION(allDofs, std::invalid_argument, "Ifpack2 candidates use the free-DOF map");
    auto prec = Ifpack2::Factory::create<RowMatrix>(cand.get<std::string>("Ifpack2 Type", "RILUK"), A);
    prec->setParameters(params);
    prec->initialize();
    prec->compute();
    M = prec;
  } else if (precType == "MueLu") {
    auto& user = params.sublist("user data");
    user.set("Nullspace", rigidBodyModes(pb, allDofs, cand.get<bool>("Zero Prescribed Nullspace", false)));
    const bool perDof = !allDofs && params.get<int>("number of equations", 1) == 1;
    if (allDofs || perDof) user.set("Coordinates", coordinates(pb, perDof));
    // On more than one rank the coarse level is gathered onto one rank: MueLu's coarse KLU2
    // (Amesos2) solves a distributed coarse matrix wrongly in this build without saying so
    // (q1+cheb2 at 80 x 40: 12 GMRES iterations on one rank, 23 on two; 12 with this).
    if (comm->getSize() > 1 && (allDofs || perDof) && !params.isParameter("repartition: enable")) {
      params.set("repartition: enable", true);
      params.set("repartition: min rows per proc", 4000);
      params.set("repartition: start level", 1);  // the default (2) leaves a two-level hierarchy's coarse level distributed
      params.set("repartition: partitioner", "zoltan2");
      params.sublist("repartition: params").set("algorithm", "multijagged");
    }
    if (verbose) params.set("verbosity", "high");
    RCP<OP> Aop = allDofs ? RCP<OP>(Aall) : RCP<OP>(A);
    auto mp = MueLu::CreateTpetraPreconditioner<double, LO, GO, Node>(Aop, params);
    auto H = mp->GetHierarchy();
    res.levels = H->GetNumLevels();
    res.complexity = H->GetOperatorComplexity();
    M = mp;
  } else if (precType == "FROSch") {
    using XCrs = Xpetra::TpetraCrsMatrix<double, LO, GO, Node>;
    using XMV = Xpetra::TpetraMultiVector<double, LO, GO, Node>;
    TEUCHOS_TEST_FOR_EXCEPTION(!allDofs, std::invalid_argument, "FROSch candidates use the all-DOF map");
    RCP<Xpetra::CrsMatrix<double, LO, GO, Node>> xc = rcp(new XCrs(Aall));
    RCP<const Xpetra::Matrix<double, LO, GO, Node>> xm = rcp(new Xpetra::CrsMatrixWrap<double, LO, GO, Node>(xc));
    auto plist = rcp(new Teuchos::ParameterList(params));
    auto prec = rcp(new FroschOperator::Prec(xm, plist));
    RCP<const Xpetra::MultiVector<double, LO, GO, Node>> ns = rcp(new XMV(rigidBodyModes(pb, true, cand.get<bool>("Zero Prescribed Nullspace", false))));
    RCP<const Xpetra::MultiVector<double, LO, GO, Node>> xyz = rcp(new XMV(coordinates(pb, false)));
    std::streambuf* keep = std::cout.rdbuf();
    std::ostringstream sink;
    if (!verbose) std::cout.rdbuf(sink.rdbuf());
    try {
      prec->initialize(D, D, cand.get<int>("Overlap", 1), ns, xyz, FROSch::NodeWise);
      prec->compute();
    } catch (...) {
      std::cout.rdbuf(keep);
      throw;
    }
    std::cout.rdbuf(keep);
    M = rcp(new FroschOperator(prec, pb.allMap));
  } else if (precType != "None") {
    throw std::invalid_argument("unknown Preconditioner '" + precType + "'");
  }
  if (!M.is_null() && allDofs) M = freeRestriction(M, ev.ownedFreeMap(), pb.freeToAll);
  if (cand.isSublist("Fine Smoother")) {
    // an Ifpack2 smoother on the assembled J around M (see twoStageOperator)
    auto& fs = cand.sublist("Fine Smoother");
    const auto tf = Clock::now();
    auto S = Ifpack2::Factory::create<RowMatrix>(fs.get<std::string>("Type", "CHEBYSHEV"), pb.J);
    S->setParameters(fs.sublist("Parameters"));
    S->initialize();
    S->compute();
    res.tFine = seconds(tf);
    if (verbose && comm->getRank() == 0) std::cout << "fine smoother: " << S->description() << std::endl;
    RCP<const OP> Jop = pb.matrixFree ? pb.Jmf : RCP<const OP>(pb.J);
    M = twoStageOperator(Jop, S, M);
  }
  comm->barrier();
  res.tSetup = seconds(t0);

  return M;
}

/// GMRES on J x = b with M on the right, stopped at the time limit; res's status, iterations,
/// solve time and true residual.
void gmresSolve(const Problem& pb, const RCP<const OP>& M, double tol, int restart, int maxIters, double timeLimit,
                bool verbose, Result& res) {
  auto comm = pb.ev->comm();
  auto b = TOE::getConstTpetraVector(pb.b);
  auto xs = rcp(new MV(b->getMap(), 1));
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeLimit));
  RCP<TimedOperator> Mt = M.is_null() ? Teuchos::null : rcp(new TimedOperator(M, deadline, comm));
  RCP<const OP> Jop = pb.matrixFree ? pb.Jmf : RCP<const OP>(pb.J);
  auto lp = rcp(new Belos::LinearProblem<double, MV, OP>(Jop, xs, Teuchos::rcp_implicit_cast<const MV>(b)));
  if (!Mt.is_null()) lp->setRightPrec(Mt);
  lp->setProblem();
  auto bp = rcp(new Teuchos::ParameterList);
  bp->set("Num Blocks", restart);
  bp->set("Maximum Iterations", maxIters);
  bp->set("Convergence Tolerance", tol);
  bp->set("Implicit Residual Scaling", "Norm of RHS");
  bp->set("Explicit Residual Scaling", "Norm of RHS");
  if (verbose) {
    bp->set("Verbosity", Belos::Errors + Belos::Warnings + Belos::StatusTestDetails);
    bp->set("Output Frequency", 20);
  }
  Belos::PseudoBlockGmresSolMgr<double, MV, OP> solver(lp, bp);
  comm->barrier();
  auto t0 = Clock::now();
  try {
    const auto r = solver.solve();
    res.status = r == Belos::Converged ? "converged" : "unconverged";
    res.iterations = solver.getNumIters();
  } catch (const TimeLimit&) {
    res.status = "time limit";
    res.iterations = static_cast<int>(Mt->applies);
  }
  comm->barrier();
  res.tSolve = seconds(t0);
  MV r(b->getMap(), 1);
  pb.J->apply(*xs, r);
  r.update(1.0, *b, -1.0);
  std::vector<double> rn(1), bn(1);
  r.norm2(Teuchos::ArrayView<double>(rn));
  b->norm2(Teuchos::ArrayView<double>(bn));
  res.trueResidual = rn[0] / bn[0];
}

Result runCandidate(const Problem& pb, Teuchos::ParameterList cand, double tol, int restart, int maxIters,
                    double timeLimit, bool verbose) {
  Result res;
  const auto matrices = preconditionerMatrix(pb, cand, res);
  const auto M = buildPreconditioner(pb, cand, matrices, res, verbose);
  gmresSolve(pb, M, tol, restart, maxIters, timeLimit, verbose, res);
  return res;
}

int usage(int code) {
  (code ? std::cerr : std::cout)
      << "usage: bench_preconditioners [--scene SCENE.xml] [--set Sublist/Key=value]... --sizes NXxNY[xNZ]...\n"
         "         --candidates NAME|FILE.xml... [--csv FILE] [--state affine|zero] [--tol 1e-10]\n"
         "         [--operator assembled|matrix-free] [--tag TEXT (first CSV column)]\n"
         "         [--restart 200] [--max-iterations 3000] [--time-limit 600] [--verbose] [--list]\n";
  return code;
}

/// The command line.
struct Options {
  std::string scenePath = std::string(PERINOX_SOURCE_DIR) + "/xml/tension_block.xml";
  std::string csvPath, state = "affine", op = "assembled", tag;
  std::vector<std::string> sets, sizes, candidates;
  double tol = 1e-10, timeLimit = 600;
  int restart = 200, maxIters = 3000;
  bool verbose = false, list = false, help = false;
};

/// Reads the command line; throws std::invalid_argument naming a bad argument.
Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    auto many = [&](std::vector<std::string>& v) {
      while (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0) v.push_back(argv[++i]);
    };
    if (a == "--scene") o.scenePath = next();
    else if (a == "--set") o.sets.push_back(next());
    else if (a == "--sizes") many(o.sizes);
    else if (a == "--candidates") many(o.candidates);
    else if (a == "--csv") o.csvPath = next();
    else if (a == "--state") o.state = next();
    else if (a == "--operator") o.op = next();
    else if (a == "--tag") o.tag = next();
    else if (a == "--tol") o.tol = std::stod(next());
    else if (a == "--restart") o.restart = std::stoi(next());
    else if (a == "--max-iterations") o.maxIters = std::stoi(next());
    else if (a == "--time-limit") o.timeLimit = std::stod(next());
    else if (a == "--verbose") o.verbose = true;
    else if (a == "--list") o.list = true;
    else if (a == "--help" || a == "-h") o.help = true;
    else throw std::invalid_argument("unknown argument '" + a + "'");
  }
  return o;
}

/// A candidate by name (built in) or from an XML file; its display name in cname. Throws on an
/// unknown name.
Teuchos::ParameterList candidateNamed(const std::string& name, const std::map<std::string, Teuchos::ParameterList>& builtins,
                                      int D, const Teuchos::Comm<int>& comm, std::string& cname) {
  Teuchos::ParameterList cand;
  cname = name;
  if (name.size() > 4 && name.substr(name.size() - 4) == ".xml") {
    Teuchos::updateParametersFromXmlFileAndBroadcast(name, Teuchos::ptrFromRef(cand), comm);
    cname = name.substr(name.find_last_of('/') + 1);
    cname = cname.substr(0, cname.size() - 4);
    if (cand.isSublist("Parameters") && cand.get<std::string>("Preconditioner", "") == "MueLu" &&
        !cand.sublist("Parameters").isParameter("number of equations"))
      cand.sublist("Parameters").set("number of equations", cand.get<std::string>("DOF Map", "Free") == "All" ? D : 1);
    return cand;
  }
  auto it = builtins.find(name);
  if (it == builtins.end()) throw std::invalid_argument("unknown candidate '" + name + "' (--list shows them)");
  return it->second;
}

/// The console line and CSV row of one candidate's result.
void report(const Options& o, const Problem& pb, const std::string& size, const std::string& cname,
            Teuchos::ParameterList cand, const Result& r, int ranks, std::ofstream& csv) {
  const double tr = pb.tResidual;
  const double setupR = (r.tMatrix + r.tSetup) / tr, solveR = r.tSolve / tr;
  const double perIt = r.iterations > 0 ? solveR / r.iterations : NAN;
  std::printf("%-10s %9lld %9lld %-20s %6d %5s %4d %6.2f %9.1e %8.4f %8.2f %8.2f %8.1f %8.1f %8.1f %8.1f %8.1f %9.1f%s%s\n",
              size.c_str(), pb.realParticles, pb.ev->numFreeDofs(), cname.c_str(), r.iterations,
              r.status == "converged" ? "yes" : (r.status == "time limit" ? "time" : "no"), r.levels,
              r.complexity, r.trueResidual, tr, pb.tMatvec / tr, pb.tJvMf / tr, pb.tAssemble / tr, r.tOnce / tr, r.tMatrix / tr,
              r.tSetup / tr, solveR, setupR + solveR, r.note.empty() ? "" : "  ", r.note.substr(0, 120).c_str());
  std::fflush(stdout);
  if (!csv.is_open()) return;
  csv << o.tag << ',' << size << ',' << pb.realParticles << ',' << pb.ev->numFreeDofs() << ',' << ranks << ','
      << o.state << ',' << o.op << ',' << cname << ',' << cand.get<std::string>("Matrix", "Jacobian") << ','
      << cand.get<std::string>("DOF Map", "Free") << ',' << cand.get<std::string>("Preconditioner", "None")
      << ',' << r.precNnz << ',' << r.levels << ',' << r.complexity << ',' << r.status << ','
      << r.iterations << ',' << r.trueResidual << ',' << tr << ',' << pb.tMatvec << ',' << pb.tJvMf
      << ',' << pb.tAssemble << ',' << r.tOnce << ',' << r.tMatrix << ',' << r.tFine << ',' << r.tSetup << ',' << r.tSolve << ','
      << setupR << ',' << solveR << ',' << setupR + solveR << ',' << perIt << ',' << r.note << '\n';
  csv.flush();
}

/// An empty CSV file (or none yet) gets the header row first.
void openCsv(const std::string& path, std::ofstream& csv) {
  std::ifstream probe(path);
  const bool fresh = !probe.good() || probe.peek() == std::ifstream::traits_type::eof();
  csv.open(path, std::ios::app);
  if (fresh)
    csv << "tag,lattice,particles,free_dofs,ranks,state,operator,candidate,matrix,dof_map,preconditioner,prec_nnz,levels,"
           "op_complexity,status,iterations,true_rel_residual,t_residual_s,t_matvec_s,t_jv_matrix_free_s,"
           "t_assemble_J_s,t_once_s,t_prec_matrix_s,t_fine_smoother_s,t_setup_s,t_solve_s,setup_in_residuals,solve_in_residuals,total_in_residuals,"
           "per_iteration_in_residuals,note\n";
}

}  // namespace

int main(int argc, char** argv) {
  Tpetra::ScopeGuard guard(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const bool root = comm->getRank() == 0;
  Options o;
  try {
    o = parseOptions(argc, argv);
  } catch (const std::exception& e) {
    if (root) std::cerr << "bench_preconditioners: " << e.what() << "\n";
    return root ? usage(2) : 2;
  }
  if (o.help) return root ? usage(0) : 0;
  if (o.list) {
    if (root)
      for (const auto& [name, p] : builtinCandidates(2)) {
        std::cout << "== " << name << "\n";
        p.print(std::cout, 2);
      }
    return 0;
  }
  if (o.sizes.empty() || o.candidates.empty()) return root ? usage(2) : 2;
  std::ofstream csv;
  if (root && !o.csvPath.empty()) openCsv(o.csvPath, csv);
  if (root)
    std::printf("%-10s %9s %9s %-20s %6s %5s %4s %6s %9s %8s %8s %8s %8s %8s %8s %8s %8s %9s\n", "lattice", "particles",
                "free DOFs", "candidate", "iters", "conv", "lev", "cplx", "true res", "res s", "matvec/r", "mfJv/r",
                "asmJ/r", "once/r", "matrix/r", "setup/r", "solve/r", "total/r");
  const std::string presetDir = std::string(PERINOX_SOURCE_DIR) + "/xml/solvers";
  for (const auto& size : o.sizes) {
    Problem pb;
    try {
      pb = buildProblem(comm, o.scenePath, o.sets, size, o.state, presetDir);
      pb.matrixFree = o.op == "matrix-free";
    } catch (const std::exception& e) {
      if (root) std::cerr << "bench_preconditioners: size " << size << ": " << e.what() << "\n";
      return 2;
    }
    const int D = pb.ev->problem().dim();
    const auto builtins = builtinCandidates(D);
    for (const auto& name : o.candidates) {
      Teuchos::ParameterList cand;
      std::string cname;
      try {
        cand = candidateNamed(name, builtins, D, *comm, cname);
      } catch (const std::invalid_argument& e) {
        if (root) std::cerr << "bench_preconditioners: " << e.what() << "\n";
        return 2;
      }
      Result r;
      try {
        r = runCandidate(pb, cand, o.tol, o.restart, o.maxIters, o.timeLimit, o.verbose);
      } catch (const std::exception& e) {
        r.status = "failed";
        std::string msg = e.what();
        for (char& ch : msg)
          if (ch == '\n' || ch == ',' || ch == '"') ch = ' ';
        r.note = msg.substr(0, 300);
      }
      if (root) report(o, pb, size, cname, cand, r, comm->getSize(), csv);
    }
  }
  return 0;
}
