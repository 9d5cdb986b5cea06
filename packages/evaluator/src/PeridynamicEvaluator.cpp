#include "perinox/evaluator/PeridynamicEvaluator.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Thyra_DefaultLinearOpSource.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Eigen/Geometry>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <limits>
#include <optional>
#include <cmath>
#include <sstream>

#include "perinox/model/Partition.hpp"

namespace perinox {

using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;
using MEB = Thyra::ModelEvaluatorBase;

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
    const std::vector<LO>* ovColToOwned = nullptr;
    bool active = false;                  // a Jacobian is wanted (a rank may own no entries)
  };
  TpetraSink(int dim, double* r, const std::vector<int>& freeLid, const OwnedRows& owned, TCrsMatrix* ghost)
      : D_(dim), r_(r), freeLid_(freeLid), owned_(owned), ghost_(ghost) {}

  void add(const int* parts, int n, const double* re, const double* Ke) override {
    const int nd = n * D_;
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < D_; ++c) r_[parts[a] * D_ + c] += re[a * D_ + c];
    if (!Ke || !owned_.active) return;
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
    for (int a = 0; a < n; ++a) {
      std::size_t mergedLength = static_cast<std::size_t>(-1);  // row length the offsets belong to
      for (int c = 0; c < D_; ++c) {
        const int row = freeLid_[parts[a] * D_ + c];
        if (row < 0) continue;
        const double* Krow = Ke + static_cast<std::size_t>(a * D_ + c) * nd;
        if (row < owned_.numRows) {
          const size_t begin = owned_.rowPtr[row], length = owned_.rowPtr[row + 1] - begin;
          const LO* rc = owned_.cols + begin;
          if (length != mergedLength) {  // merge the sorted element columns with the sorted row
            size_t k = 0;
            for (std::size_t q = 0; q < sorted_.size(); ++q) {
              const LO col = sorted_[q].first;
              while (k < length && rc[k] < col) ++k;
              offsets_[q] = k < length && rc[k] == col ? static_cast<long>(k) : -1;
            }
            mergedLength = length;
          }
          double* v = owned_.values + begin;
          for (std::size_t q = 0; q < sorted_.size(); ++q)
            if (offsets_[q] >= 0) v[offsets_[q]] += Krow[sorted_[q].second];
        } else if (ghost_) {
          for (std::size_t q = 0; q < cols_.size(); ++q) vals_[q] = Krow[pos_[q]];
          ghost_->sumIntoLocalValues(row - owned_.numRows, static_cast<LO>(cols_.size()), vals_.data(), cols_.data());
        }
      }
    }
  }

 private:
  int D_;
  double* r_;
  const std::vector<int>& freeLid_;
  OwnedRows owned_;
  TCrsMatrix* ghost_;
  std::vector<LO> cols_;
  std::vector<int> pos_;
  std::vector<std::pair<LO, int>> sorted_;  // (owned column lid, position in the element) by column
  std::vector<long> offsets_;               // position of each sorted column in the current row
  std::vector<double> vals_;
};

}  // namespace

/// The analytic matrix-free Jacobian: W v = (df_int/du) v from the linearised kernels at the
/// state of the last evaluation with W_op (its displacements are kept; nothing is assembled).
class JacobianOperator final : public Tpetra::Operator<double, LO, GO, Node> {
 public:
  explicit JacobianOperator(const PeridynamicEvaluator& ev) : ev_(ev) {}
  Teuchos::RCP<const TMap> getDomainMap() const override { return ev_.ownedFree_; }
  Teuchos::RCP<const TMap> getRangeMap() const override { return ev_.ownedFree_; }
  bool hasTransposeApply() const override { return false; }
  void setState(std::vector<double> u) { u_ = std::move(u); }
  void apply(const Tpetra::MultiVector<double, LO, GO, Node>& X, Tpetra::MultiVector<double, LO, GO, Node>& Y,
             Teuchos::ETransp mode, double alpha, double beta) const override {
    TEUCHOS_TEST_FOR_EXCEPTION(mode != Teuchos::NO_TRANS, std::logic_error,
                               "the matrix-free Jacobian has no transpose product");
    TEUCHOS_TEST_FOR_EXCEPTION(u_.empty(), std::logic_error, "the matrix-free Jacobian was applied before evaluation");
    const size_t n = X.getLocalLength();
    std::vector<double> y(n);
    for (size_t k = 0; k < X.getNumVectors(); ++k) {
      auto xd = X.getData(k);
      ev_.applyJacobian(u_, xd.getRawPtr(), y.data());
      auto yd = Y.getDataNonConst(k);
      for (size_t r = 0; r < n; ++r) yd[r] = (beta == 0.0 ? 0.0 : beta * yd[r]) + alpha * y[r];
    }
  }

 private:
  const PeridynamicEvaluator& ev_;
  std::vector<double> u_;
};

/// The Jacobian-free product: W v = (f(x + h v) - f(x)) / h, one residual evaluation per
/// product. NOX's own difference operator takes an absolute floor of lambda^2 for the step,
/// which in SI units (displacements of 1e-3 m, Krylov vectors of 1e-10 m after an ILU
/// preconditioner) is lost in the residual's round-off; here the step is relative to the
/// displacement scale: h |v|_inf = lambda max(|x|_inf, dx).
class DifferenceJacobianOperator final : public Tpetra::Operator<double, LO, GO, Node> {
 public:
  explicit DifferenceJacobianOperator(const PeridynamicEvaluator& ev) : ev_(ev) {}
  Teuchos::RCP<const TMap> getDomainMap() const override { return ev_.ownedFree_; }
  Teuchos::RCP<const TMap> getRangeMap() const override { return ev_.ownedFree_; }
  bool hasTransposeApply() const override { return false; }
  void setState(const Thyra::VectorBase<double>& x) {
    x_ = x.clone_v();
    f0_ = Thyra::createMember(x.space());
    evalF(*x_, *f0_);
  }
  void apply(const Tpetra::MultiVector<double, LO, GO, Node>& X, Tpetra::MultiVector<double, LO, GO, Node>& Y,
             Teuchos::ETransp mode, double alpha, double beta) const override {
    TEUCHOS_TEST_FOR_EXCEPTION(mode != Teuchos::NO_TRANS, std::logic_error,
                               "the Jacobian-free operator has no transpose product");
    TEUCHOS_TEST_FOR_EXCEPTION(x_.is_null(), std::logic_error, "the Jacobian-free operator was applied before evaluation");
    const double scale = std::max(Thyra::norm_inf(*x_), ev_.problem().disc.dx);
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
      const double h = ev_.fdLambda_ * scale / vinf;
      Thyra::V_StVpV(xp.ptr(), h, *v, *x_);
      evalF(*xp, *fp);
      Thyra::Vp_StV(fp.ptr(), -1.0, *f0_);
      auto fpt = TOE::getConstTpetraVector(fp);
      yk->update(alpha / h, *fpt, beta);
    }
  }

 private:
  void evalF(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& f) const {
    auto in = ev_.createInArgs();
    in.set_x(Teuchos::rcpFromRef(x));
    auto out = ev_.createOutArgs();
    out.set_f(Teuchos::rcpFromRef(f));
    ev_.evalModel(in, out);
  }
  const PeridynamicEvaluator& ev_;
  Teuchos::RCP<Thyra::VectorBase<double>> x_, f0_;
};

PeridynamicEvaluator::PeridynamicEvaluator(Teuchos::RCP<const Teuchos::Comm<int>> comm,
                                           std::shared_ptr<const ProblemSpec> problem)
    : comm_(comm), problem_(std::move(problem)) {
  if (!problem_) throw std::invalid_argument("ProblemSpec: the evaluator was given no problem");
  validateProblem(*problem_);
  const ProblemSpec& P = *problem_;
  const long long n = P.disc.size();
  begin_ = partitionBegin(n, comm_->getSize(), comm_->getRank());
  end_ = partitionBegin(n, comm_->getSize(), comm_->getRank() + 1);
  LocalParticles lp = localParticles(P.disc, begin_, end_);
  if (!P.modulusScale.empty())
    for (long long g : lp.globalId) lp.modulusScale.push_back(P.modulusScale[g]);
  model_ = std::make_unique<Model>(P.material, std::move(lp));
  if (P.stressPoints) model_->enableStressPoints(P.stressPointSeed);
  else if (P.correspondence) model_->enableCorrespondence();
  if (P.control) model_->enableControl(P.controlSpec);
  if (P.stabilization) model_->enableStabilization(P.stab);
  if (P.damage) model_->enableDamage(P.damageSpec);
  // Stiffness scale for frozen (detached) DOFs: E V / dx^2 of a particle, so the frozen rows
  // are neither negligible nor dominant in the linear solves.
  frozenStiffness_ = P.material.E * P.disc.volume.front() / (P.disc.dx * P.disc.dx);

  const int D = P.dim();
  freeId_.assign(static_cast<std::size_t>(n) * D, -1);
  for (long long p = 0; p < n; ++p)
    for (int c = 0; c < D; ++c)
      if (!P.isFixed(static_cast<int>(p), c)) freeId_[p * D + c] = numFree_++;
  buildMapsAndGraphs();

  {
    const auto scale = model_->unitStressForceScale();
    TVector ov(overlapAll_), owned(ownedAll_);
    auto od = ov.getDataNonConst();
    for (int l = 0; l < model_->particles().size(); ++l)
      for (int c = 0; c < D; ++c) od[l * D + c] = scale[l];
    od = Teuchos::null;
    owned.doExport(ov, *allExport_, Tpetra::ADD);
    auto wd = owned.getData();
    double s2 = 0, g2 = 0;
    for (int l = 0; l < model_->particles().numOwned; ++l)
      for (int c = 0; c < D; ++c)
        if (overlapFreeLid_[l * D + c] >= 0) s2 += wd[l * D + c] * wd[l * D + c];
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, s2, Teuchos::outArg(g2));
    roundoffScale_ = std::numeric_limits<double>::epsilon() * P.material.E * std::sqrt(g2);
  }
  xSpace_ = Thyra::createVectorSpace<double, LO, GO, Node>(ownedFree_);
  // The load factor: one value, replicated on every rank.
  pSpace_ = Thyra::createVectorSpace<double, LO, GO, Node>(Tpetra::createLocalMapWithNode<LO, GO, Node>(1, comm_));
  nominal_ = createInArgs();
  auto x0 = Thyra::createMember(xSpace_);
  Thyra::assign(x0.ptr(), 0.0);
  nominal_.set_x(x0);
}

void PeridynamicEvaluator::buildMapsAndGraphs() {
  const ProblemSpec& P = *problem_;
  const Discretization& d = P.disc;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  const int nLocal = lp.size();
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();

  std::vector<GO> ownedFreeG, overlapFreeG, ownedAllG, overlapAllG;
  overlapFreeLid_.assign(static_cast<std::size_t>(nLocal) * D, -1);
  for (int l = 0; l < nLocal; ++l)
    for (int c = 0; c < D; ++c) {
      const GO g = lp.globalId[l];
      overlapAllG.push_back(g * D + c);
      if (l < lp.numOwned) ownedAllG.push_back(g * D + c);
      const long long f = freeId_[g * D + c];
      if (f >= 0) {
        overlapFreeLid_[l * D + c] = static_cast<int>(overlapFreeG.size());
        overlapFreeG.push_back(f);
        if (l < lp.numOwned) ownedFreeG.push_back(f);
      }
    }
  ownedFree_ = Teuchos::rcp(new TMap(numFree_, Teuchos::ArrayView<const GO>(ownedFreeG), 0, comm_));
  overlapFree_ = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(overlapFreeG), 0, comm_));
  ownedAll_ = Teuchos::rcp(new TMap(static_cast<Tpetra::global_size_t>(d.size()) * D,
                                    Teuchos::ArrayView<const GO>(ownedAllG), 0, comm_));
  overlapAll_ = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(overlapAllG), 0, comm_));
  allImport_ = Teuchos::rcp(new Tpetra::Import<LO, GO>(ownedAll_, overlapAll_));
  allExport_ = Teuchos::rcp(new Tpetra::Export<LO, GO>(overlapAll_, ownedAll_));

  // External force on owned free DOFs at load factor 1: f_ext = V b.
  fextOwnedFree_ = Teuchos::rcp(new TVector(ownedFree_));
  {
    auto f = fextOwnedFree_->getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c)
        if (overlapFreeLid_[l * D + c] >= 0) {
          const long long g = lp.globalId[l];
          f[k++] = d.volume[g] * P.bodyForce[g * D + c];
        }
  }
  fextNorm_ = fextOwnedFree_->norm2();
}

PeridynamicEvaluator::Graphs PeridynamicEvaluator::buildGraphs(bool neighbours) const {
  const ProblemSpec& P = *problem_;
  const Discretization& d = P.disc;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  const int nLocal = lp.size();
  // With neighbours, a pair of particles is coupled only when they are within one horizon of
  // each other (the bonds themselves), not through a shared family member (two horizons).
  const double reach2 = d.horizon * d.horizon * (1.0 + 1e-10);
  auto near = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return !neighbours || (a - b).squaredNorm() <= reach2;
  };
  Graphs g;
  // Overlapping graph: every owned element {i} u H_i couples its particles.
  std::vector<std::vector<int>> adj(nLocal);
  for (int i = 0; i < lp.numOwned; ++i) {
    std::vector<int> parts{i};
    for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) parts.push_back(lp.famIndex[q]);
    for (int a : parts)
      for (int b : parts)
        if (near(lp.X[a], lp.X[b])) adj[a].push_back(b);
  }
  // Ghost-row graph: the rows of the ghost particles' free DOFs (overlap lids from the owned
  // count on), in the overlap's order; its column map is the overlap map.
  const LO nOwnedFree = static_cast<LO>(ownedFree_->getNodeNumElements());
  const LO nOverlapFree = static_cast<LO>(overlapFree_->getNodeNumElements());
  std::vector<GO> ghostRows;
  for (LO r = nOwnedFree; r < nOverlapFree; ++r) ghostRows.push_back(overlapFree_->getGlobalElement(r));
  const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
  auto ghostMap = Teuchos::rcp(new TMap(invalid, Teuchos::ArrayView<const GO>(ghostRows), 0, comm_));
  std::vector<size_t> nnzGhost(ghostRows.size(), 0);
  for (int l = lp.numOwned; l < nLocal; ++l) {
    auto& v = adj[l];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    size_t cnt = 0;
    for (int q : v)
      for (int c = 0; c < D; ++c) cnt += overlapFreeLid_[q * D + c] >= 0;
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] >= 0) nnzGhost[overlapFreeLid_[l * D + c] - nOwnedFree] = cnt;
  }
  g.ghost = Teuchos::rcp(new TCrsGraph(ghostMap, overlapFree_, Teuchos::ArrayView<const size_t>(nnzGhost)));
  std::vector<LO> cols;
  for (int l = lp.numOwned; l < nLocal; ++l) {
    cols.clear();
    for (int q : adj[l])
      for (int c = 0; c < D; ++c)
        if (overlapFreeLid_[q * D + c] >= 0) cols.push_back(overlapFreeLid_[q * D + c]);
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] >= 0)
        g.ghost->insertLocalIndices(overlapFreeLid_[l * D + c] - nOwnedFree, Teuchos::ArrayView<const LO>(cols));
  }
  adj.clear();
  adj.shrink_to_fit();
  g.ghost->fillComplete(ownedFree_, ownedFree_);
  int mine = ghostRows.empty() ? 0 : 1, any = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(any));
  g.anyGhost = any != 0;
  g.ghostExport = Teuchos::rcp(new Tpetra::Export<LO, GO>(ghostMap, ownedFree_));

  // Owned graph, computed from the replicated families: row particle p couples to every
  // particle of every element that contains p, i.e. of {i} u H_i for i in {p} u H_p (only
  // those within one horizon of p with neighbours).
  std::vector<size_t> nnz;
  std::vector<std::vector<GO>> rowCols;
  std::vector<GO> rows;
  std::vector<long long> S;
  for (long long p = begin_; p < end_; ++p) {
    S.clear();
    auto addElement = [&](long long i) {
      S.push_back(i);
      for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q) S.push_back(d.familyIndex[q]);
    };
    addElement(p);
    for (auto q = d.familyOffset[p]; q < d.familyOffset[p + 1]; ++q) addElement(d.familyIndex[q]);
    std::sort(S.begin(), S.end());
    S.erase(std::unique(S.begin(), S.end()), S.end());
    std::vector<GO> gc;
    for (long long s : S)
      if (near(d.X[p], d.X[s]))
        for (int c = 0; c < D; ++c)
          if (freeId_[s * D + c] >= 0) gc.push_back(freeId_[s * D + c]);
    for (int c = 0; c < D; ++c)
      if (freeId_[p * D + c] >= 0) {
        nnz.push_back(gc.size());
        rowCols.push_back(gc);
        rows.push_back(freeId_[p * D + c]);
      }
  }
  g.owned = Teuchos::rcp(new TCrsGraph(ownedFree_, Teuchos::ArrayView<const size_t>(nnz)));
  for (size_t r = 0; r < rowCols.size(); ++r)
    g.owned->insertGlobalIndices(rows[r], Teuchos::ArrayView<const GO>(rowCols[r]));
  g.owned->fillComplete(ownedFree_, ownedFree_);
  // The sink's binary search needs each row's column lids sorted (Tpetra sorts them when it
  // fills a graph, but say so if a build ever does not).
  if (!g.owned->isSorted()) throw std::logic_error("perinox: the Jacobian graph's rows are not sorted");
  g.ovColToOwned.assign(nOverlapFree, -1);
  for (LO c = 0; c < nOverlapFree; ++c) {
    const LO k = g.owned->getColMap()->getLocalElement(overlapFree_->getGlobalElement(c));
    if (k != Teuchos::OrdinalTraits<LO>::invalid()) g.ovColToOwned[c] = k;
  }
  g.ghostMatrix = Teuchos::rcp(new TCrsMatrix(g.ghost));
  g.ghostMatrix->fillComplete(ownedFree_, ownedFree_);
  return g;
}

const PeridynamicEvaluator::Graphs& PeridynamicEvaluator::graphs(bool neighbours) const {
  Graphs& g = neighbours ? nbr_ : full_;
  if (g.owned.is_null()) g = buildGraphs(neighbours);
  return g;
}

MEB::InArgs<double> PeridynamicEvaluator::getNominalValues() const {
  MEB::InArgs<double> nominal = nominal_;
  auto p = Thyra::createMember(pSpace_);
  Thyra::set_ele(0, lambda_, p.ptr());
  nominal.set_p(0, p);
  return nominal;
}

MEB::InArgs<double> PeridynamicEvaluator::createInArgs() const {
  MEB::InArgsSetup<double> in;
  in.setModelEvalDescription("perinox peridynamics");
  in.set_Np(1);
  in.setSupports(MEB::IN_ARG_x);
  return in;
}

Teuchos::RCP<const Thyra::VectorSpaceBase<double>> PeridynamicEvaluator::get_p_space(int l) const {
  TEUCHOS_TEST_FOR_EXCEPTION(l != 0, std::invalid_argument, "perinox's evaluator has one parameter (p(0), the load factor), not p(" << l << ")");
  return pSpace_;
}

Teuchos::RCP<const Teuchos::Array<std::string>> PeridynamicEvaluator::get_p_names(int l) const {
  TEUCHOS_TEST_FOR_EXCEPTION(l != 0, std::invalid_argument, "perinox's evaluator has one parameter (p(0), the load factor), not p(" << l << ")");
  return Teuchos::rcp(new Teuchos::Array<std::string>(1, "Load Factor"));
}

void PeridynamicEvaluator::loadDerivative(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& fl) const {
  const double lambda = lambda_;
  auto fm = fl.clone_v();
  auto residualAt = [&](double l, Thyra::VectorBase<double>& f) {
    lambda_ = l;
    auto in = createInArgs();
    in.set_x(Teuchos::rcpFromRef(x));
    auto out = createOutArgs();
    out.set_f(Teuchos::rcpFromRef(f));
    evalModel(in, out);
  };
  double h = 0.5;  // dead loads: f is linear in lambda, f(1) - f(0) exactly
  if (problem_->prescribesDisplacement()) {
    h = 1e-6 * std::max(1.0, std::abs(lambda));
    residualAt(lambda + h, fl);
    residualAt(lambda - h, *fm);
  } else {
    residualAt(1.0, fl);
    residualAt(0.0, *fm);
  }
  lambda_ = lambda;
  Thyra::Vp_StV(Teuchos::ptrFromRef(fl), -1.0, *fm);
  if (problem_->prescribesDisplacement()) Thyra::scale(0.5 / h, Teuchos::ptrFromRef(fl));
}

MEB::OutArgs<double> PeridynamicEvaluator::createOutArgsImpl() const {
  MEB::OutArgsSetup<double> out;
  out.setModelEvalDescription("perinox peridynamics");
  out.setSupports(MEB::OUT_ARG_f);
  out.setSupports(MEB::OUT_ARG_W_op);
  if (!precFactory_.is_null()) out.setSupports(MEB::OUT_ARG_W_prec);
  out.set_Np_Ng(1, 0);
  out.setSupports(MEB::OUT_ARG_DfDp, 0, MEB::DerivativeSupport(MEB::DERIV_MV_BY_COL));
  return out;
}

Teuchos::RCP<Thyra::LinearOpBase<double>> PeridynamicEvaluator::create_W_op() const {
  Teuchos::RCP<Tpetra::Operator<double, LO, GO, Node>> op;
  if (mode_ == JacobianMode::MatrixFree) {
    op = Teuchos::rcp(new JacobianOperator(*this));
  } else if (mode_ == JacobianMode::JacobianFree) {
    op = Teuchos::rcp(new DifferenceJacobianOperator(*this));
  } else {
    auto A = Teuchos::rcp(new TCrsMatrix(graphs(false).owned));
    A->fillComplete();
    op = A;
  }
  return Thyra::createLinearOp<double, LO, GO, Node>(op, xSpace_, xSpace_);
}

Teuchos::RCP<Thyra::PreconditionerBase<double>> PeridynamicEvaluator::create_W_prec() const {
  if (precFactory_.is_null()) return Teuchos::null;
  return precFactory_->createPrec();
}

void PeridynamicEvaluator::setJacobian(JacobianMode mode, PreconditionerMatrix pm,
                                       Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> precFactory,
                                       double fdLambda) {
  mode_ = mode;
  fdLambda_ = fdLambda;
  precMatrixKind_ = pm;
  precFactory_ = precFactory;
  if (!precFactory_.is_null()) {
    // MueLu: hand it the rigid-body modes as near-null space (through the factory's list).
    auto pl = precFactory_->getNonconstParameterList();
    if (!pl.is_null() && pl->isParameter("multigrid algorithm")) pl->set("Nullspace", rigidBodyModes());
  }
}

Teuchos::RCP<Tpetra::MultiVector<double, LO, GO>> PeridynamicEvaluator::rigidBodyModes() const {
  const int D = problem_->dim();
  const int nModes = D == 1 ? 1 : (D == 2 ? 3 : 6);
  auto B = Teuchos::rcp(new Tpetra::MultiVector<double, LO, GO>(ownedFree_, nModes));
  const LocalParticles& lp = model_->particles();
  // Rotations about the centroid of the body, scaled by the horizon so every mode has
  // entries of order one.
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& X : problem_->disc.X) c += X;
  c /= static_cast<double>(problem_->disc.size());
  const double L = problem_->disc.horizon;
  for (int m = 0; m < nModes; ++m) {
    auto col = B->getDataNonConst(m);
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l) {
      const Eigen::Vector3d r = (lp.X[l] - c) / L;
      for (int a = 0; a < D; ++a) {
        if (overlapFreeLid_[l * D + a] < 0) continue;
        double v = 0;
        if (m < D) {
          v = m == a ? 1.0 : 0.0;
        } else if (D == 2) {  // in-plane rotation: (-y, x)
          v = a == 0 ? -r[1] : r[0];
        } else {  // rotation about axis m - 3: omega x r
          Eigen::Vector3d w = Eigen::Vector3d::Zero();
          w[m - 3] = 1.0;
          v = w.cross(r)[a];
        }
        col[k++] = v;
      }
    }
  }
  return B;
}

Teuchos::RCP<TCrsMatrix> PeridynamicEvaluator::assembledJacobian(const Thyra::VectorBase<double>& x,
                                                                 bool neighbours) const {
  auto A = Teuchos::rcp(new TCrsMatrix(graphs(neighbours).owned));
  A->fillComplete();
  internalForce(x, A.get(), neighbours);
  return A;
}

std::size_t PeridynamicEvaluator::matrixBytes() const {
  std::size_t b = 0;
  for (const Graphs* g : {&full_, &nbr_}) {
    if (g->owned.is_null()) continue;
    // values (8 B) and local column indices (4 B) per entry, row offsets (8 B) per row, for the
    // owned and the ghost-row matrix (the graphs share their indices with the matrices).
    for (const auto& gr : {g->owned, g->ghost})
      b += gr->getNodeNumEntries() * (8 + 4) + (gr->getNodeNumRows() + 1) * 8;
  }
  return b;
}

std::vector<double> PeridynamicEvaluator::localDisplacements(const Thyra::VectorBase<double>& x) const {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  auto xt = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x));
  auto xd = xt->getData();
  std::optional<Eigen::Matrix3d> rotation;
  if (P.rotates()) rotation = rotationMatrix();
  TVector uOwned(ownedAll_);
  {
    auto ud = uOwned.getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c) {
        const long long g = lp.globalId[l];
        if (overlapFreeLid_[l * D + c] >= 0) {
          const double v = xd[k++];
          if (!std::isfinite(v)) {
            std::ostringstream s;
            s << "displacement component " << c << " of particle " << g << " is not finite";
            throw EvaluationError(s.str(), g);
          }
          ud[l * D + c] = v;
        } else if (!rotation) {
          ud[l * D + c] = lambda_ * P.prescribed[g * D + c];
        } else {
          // Superposed rotation: every component of a prescribed particle is prescribed (the
          // scene checks), so the particle goes to R (X + lambda u_bar - c) + c.
          Vec3 ub = Vec3::Zero();
          for (int a = 0; a < D; ++a) ub[a] = P.prescribed[g * D + a];
          const Vec3 X = P.disc.X[g];
          const Vec3 y = (*rotation) * (X + lambda_ * ub - P.rotation.center) + P.rotation.center;
          ud[l * D + c] = y[c] - X[c];
        }
      }
  }
  TVector uOv(overlapAll_);
  uOv.doImport(uOwned, *allImport_, Tpetra::INSERT);
  auto od = uOv.getData();
  return std::vector<double>(od.begin(), od.end());
}

Teuchos::RCP<TVector> PeridynamicEvaluator::internalForce(const Thyra::VectorBase<double>& x,
                                                           TCrsMatrix* W, bool neighbours) const {
  const std::vector<double> u = localDisplacements(x);
  const Graphs* g = W ? &graphs(neighbours) : nullptr;
  TCrsMatrix* ghost = g && g->anyGhost ? g->ghostMatrix.get() : nullptr;
  TVector rOv(overlapAll_);
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
    rows.numRows = static_cast<LO>(ownedFree_->getNodeNumElements());
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
    TpetraSink sink(problem_->dim(), rd.getRawPtr(), overlapFreeLid_, rows, ghost);
    try {
      model_->evaluate(u, sink, W != nullptr);
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  if (ghost) ghost->fillComplete(ownedFree_, ownedFree_);
  synchroniseFailure(failed, message, particle);
  auto r = Teuchos::rcp(new TVector(ownedAll_));
  r->doExport(rOv, *allExport_, Tpetra::ADD);
  if (W) {
    if (ghost) W->doExport(*ghost, *g->ghostExport, Tpetra::ADD);
    for (const auto& [lid, value] : frozen_) {
      (void)value;
      const LO col = W->getColMap()->getLocalElement(ownedFree_->getGlobalElement(lid));
      W->sumIntoLocalValues(lid, 1, &frozenStiffness_, &col);
    }
    W->fillComplete(ownedFree_, ownedFree_);
  }
  return r;
}

void PeridynamicEvaluator::synchroniseFailure(int failed, std::string message, long long particle) const {
  int anyFailed = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, failed, Teuchos::outArg(anyFailed));
  if (anyFailed) {
    // Report the lowest-ranked failure so every rank throws the same sentence.
    long long pmin = failed ? particle : std::numeric_limits<long long>::max();
    long long pglob = pmin;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, pmin, Teuchos::outArg(pglob));
    if (!failed || particle != pglob) {
      std::ostringstream s;
      s << "evaluation failed at particle " << pglob;
      message = s.str();
    }
    throw EvaluationError(message, pglob);
  }
}

void PeridynamicEvaluator::applyJacobian(const std::vector<double>& u, const double* v, double* y) const {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  // Direction on all owned DOFs (prescribed ones do not move), then onto the ghosts.
  TVector vOwned(ownedAll_);
  {
    auto vd = vOwned.getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c) vd[l * D + c] = overlapFreeLid_[l * D + c] >= 0 ? v[k++] : 0.0;
  }
  if (!jvOverlap_) {
    jvOverlap_ = Teuchos::rcp(new TVector(overlapAll_));
    jvOwned_ = Teuchos::rcp(new TVector(ownedAll_));
  }
  TVector vOv(overlapAll_);
  vOv.doImport(vOwned, *allImport_, Tpetra::INSERT);
  jvOverlap_->putScalar(0.0);
  int failed = 0;
  std::string message;
  long long particle = -1;
  {
    auto vd = vOv.getData();
    const std::vector<double> vl(vd.begin(), vd.end());
    auto jd = jvOverlap_->getDataNonConst();
    try {
      model_->applyTangent(u, vl, jd.getRawPtr());
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  synchroniseFailure(failed, message, particle);
  jvOwned_->doExport(*jvOverlap_, *allExport_, Tpetra::ADD);
  auto jd = jvOwned_->getData();
  LO k = 0;
  for (int l = 0; l < lp.numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] >= 0) y[k++] = jd[l * D + c];
  for (const auto& [lid, value] : frozen_) {
    (void)value;
    y[lid] = frozenStiffness_ * v[lid];
  }
}

void PeridynamicEvaluator::evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const {
  const auto x = in.get_x();
  if (in.Np() > 0 && !in.get_p(0).is_null()) lambda_ = Thyra::get_ele(*in.get_p(0), 0);
  if (out.Np() > 0) {
    const auto dfdp = out.get_DfDp(0).getMultiVector();
    if (!dfdp.is_null()) loadDerivative(*x, *dfdp->col(0));
  }
  const auto f = out.get_f();
  const auto Wop = out.get_W_op();
  Teuchos::RCP<Thyra::PreconditionerBase<double>> Wprec;
  if (out.supports(MEB::OUT_ARG_W_prec)) Wprec = out.get_W_prec();
  if (!Wprec.is_null()) {
    // The preconditioner: Ifpack2 or MueLu on the assembled Jacobian or on its part that
    // couples direct neighbours only (memory proportional to the family size).
    precA_ = assembledJacobian(*x, precMatrixKind_ == PreconditionerMatrix::Neighbours);
    auto op = Thyra::createConstLinearOp<double, LO, GO, Node>(
        Teuchos::rcp_implicit_cast<const Tpetra::Operator<double, LO, GO, Node>>(precA_), xSpace_, xSpace_);
    precFactory_->initializePrec(Thyra::defaultLinearOpSource<double>(op), Wprec.get());
  }
  if (f.is_null() && Wop.is_null()) return;
  TCrsMatrix* W = nullptr;
  if (!Wop.is_null()) {
    auto op = TOE::getTpetraOperator(Wop);
    if (auto* J = dynamic_cast<JacobianOperator*>(op.get())) {
      J->setState(localDisplacements(*x));
      if (f.is_null()) return;
    } else if (auto* Jd = dynamic_cast<DifferenceJacobianOperator*>(op.get())) {
      Jd->setState(*x);
      if (f.is_null()) return;
    } else {
      W = &dynamic_cast<TCrsMatrix&>(*op);
    }
  }
  auto fint = internalForce(*x, W);
  if (!f.is_null()) {
    if (!(externalForceNorm() > 0)) {
      reactionNorm_ = reactionNormOf(*fint);
      reactionLambda_ = lambda_;
      if (reactionX_.is_null()) reactionX_ = x->clone_v();
      else Thyra::copy(*x, reactionX_.ptr());
    }
    auto ft = TOE::getTpetraVector(f);
    auto fd = ft->getDataNonConst();
    auto rd = fint->getData();
    auto fe = fextOwnedFree_->getData();
    const int D = problem_->dim();
    LO k = 0;
    const LocalParticles& lp = model_->particles();
    if (!problem_->rotates()) {
      for (int l = 0; l < lp.numOwned; ++l)
        for (int c = 0; c < D; ++c)
          if (overlapFreeLid_[l * D + c] >= 0) {
            fd[k] = rd[l * D + c] - lambda_ * fe[k];
            ++k;
          }
    } else {
      // Dead loads turn with the body: lambda R f_bar. A free particle has all its components
      // free (the scene checks), so its f_bar is fe[k .. k + D - 1].
      const Eigen::Matrix3d R = rotationMatrix();
      for (int l = 0; l < lp.numOwned; ++l) {
        if (overlapFreeLid_[l * D] < 0) continue;
        Vec3 fb = Vec3::Zero();
        for (int a = 0; a < D; ++a) fb[a] = fe[k + a];
        const Vec3 fr = R * fb;
        for (int c = 0; c < D; ++c, ++k) fd[k] = rd[l * D + c] - lambda_ * fr[c];
      }
    }
    if (!frozen_.empty()) {
      auto xd = TOE::getConstTpetraVector(x)->getData();
      for (const auto& [lid, value] : frozen_) fd[lid] = frozenStiffness_ * (xd[lid] - value);
    }
  }
}

PeridynamicEvaluator::BreakReport PeridynamicEvaluator::breakBonds(const Thyra::VectorBase<double>& x) {
  BreakReport rep;
  reactionX_ = Teuchos::null;
  const auto u = localDisplacements(x);
  long long local = model_->breakBonds(u);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(rep.brokenBonds));
  detachSingular(x, rep);
  return rep;
}

PeridynamicEvaluator::BreakReport PeridynamicEvaluator::breakMostStretched(const Thyra::VectorBase<double>& x,
                                                                          double tol, double& maxStretch) {
  BreakReport rep;
  reactionX_ = Teuchos::null;
  const auto u = localDisplacements(x);
  const double mine = model_->maxIntactStretch(u);
  maxStretch = mine;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(maxStretch));
  if (!problem_->damage || !(maxStretch >= problem_->damageSpec.sMin)) return rep;
  long long local = model_->breakBondsAbove(u, maxStretch - tol);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(rep.brokenBonds));
  detachSingular(x, rep);
  return rep;
}

std::vector<std::pair<long long, long long>> PeridynamicEvaluator::ownedBrokenBonds() const {
  // The model's owned families start as the discretisation's (Partition.cpp) and only lose bonds.
  const auto& d = problem_->disc;
  const LocalParticles& lp = model_->particles();
  std::vector<std::pair<long long, long long>> out;
  std::vector<long long> now;
  for (int i = 0; i < lp.numOwned; ++i) {
    const long long g = lp.globalId[i];
    now.clear();
    for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) now.push_back(lp.globalId[lp.famIndex[q]]);
    std::sort(now.begin(), now.end());
    for (auto q = d.familyOffset[g]; q < d.familyOffset[g + 1]; ++q)
      if (!std::binary_search(now.begin(), now.end(), d.familyIndex[q])) out.emplace_back(g, d.familyIndex[q]);
  }
  return out;
}

std::vector<std::pair<long long, double>> PeridynamicEvaluator::ownedFreeValues(const Thyra::VectorBase<double>& x) const {
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  std::vector<std::pair<long long, double>> out;
  out.reserve(xd.size());
  for (LO l = 0; l < static_cast<LO>(xd.size()); ++l) out.emplace_back(ownedFree_->getGlobalElement(l), xd[l]);
  return out;
}

void PeridynamicEvaluator::setOwnedFreeValues(Thyra::VectorBase<double>& x,
                                              const std::vector<std::pair<long long, double>>& values) const {
  auto xd = TOE::getTpetraVector(Teuchos::rcpFromRef(x))->getDataNonConst();
  for (const auto& [gid, value] : values) {
    const LO l = ownedFree_->getLocalElement(gid);
    if (l != Teuchos::OrdinalTraits<LO>::invalid()) xd[l] = value;
  }
}

std::vector<std::pair<long long, double>> PeridynamicEvaluator::ownedFrozenDofs() const {
  std::vector<std::pair<long long, double>> out;
  for (const auto& [lid, value] : frozen_) out.emplace_back(ownedFree_->getGlobalElement(lid), value);
  return out;
}

void PeridynamicEvaluator::restoreDamage(const std::vector<std::pair<long long, long long>>& broken,
                                         const std::vector<long long>& detached,
                                         const std::vector<std::pair<long long, double>>& frozen) {
  reactionX_ = Teuchos::null;
  std::vector<std::pair<long long, long long>> gone;
  gone.reserve(broken.size());
  for (auto [a, b] : broken) gone.emplace_back(std::min(a, b), std::max(a, b));
  std::sort(gone.begin(), gone.end());
  const LocalParticles& lp = model_->particles();
  if (!gone.empty())
    model_->removeBondsIf([&](int i, int j) {
      const long long a = lp.globalId[i], b = lp.globalId[j];
      return !std::binary_search(gone.begin(), gone.end(), std::make_pair(std::min(a, b), std::max(a, b)));
    });
  std::vector<long long> ids(detached);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  if (!ids.empty()) {
    model_->isolate(ids);
    model_->markDetached(ids);
  }
  detachedAll_ = ids;
  frozen_.clear();
  for (const auto& [gid, value] : frozen) {
    const LO lid = ownedFree_->getLocalElement(gid);
    if (lid != Teuchos::OrdinalTraits<LO>::invalid()) frozen_.emplace_back(lid, value);
  }
}

void PeridynamicEvaluator::detachSingular(const Thyra::VectorBase<double>& x, BreakReport& rep) {
  const int D = problem_->dim();
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  // Isolates, marks detached and freezes (at x) the given particles (global ids, all ranks).
  auto detach = [&](const std::vector<long long>& ids) {
    model_->isolate(ids);
    model_->markDetached(ids);
    for (long long g : ids) {
      rep.detached.push_back(g);
      detachedAll_.push_back(g);
      if (g < begin_ || g >= end_) continue;
      const int l = static_cast<int>(g - begin_);
      for (int c = 0; c < D; ++c) {
        const int lid = overlapFreeLid_[l * D + c];
        if (lid >= 0) frozen_.emplace_back(lid, xd[lid]);
      }
    }
  };
  for (int round = 0; round < 1000; ++round) {
    // Every particle that became singular on any rank (rare: after damage only).
    const auto ids = onAnyRank(model_->singularParticles());
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

std::vector<long long> PeridynamicEvaluator::unanchoredParticles() const {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  // anchored[l]: particle l (owned or ghost) reaches a prescribed DOF through intact bonds. Spread
  // over the owned families to a fixed point on each rank, then to the ghosts by an Import, until
  // no rank anchors another particle.
  std::vector<char> anchored(lp.size(), 0);
  for (int l = 0; l < lp.numOwned; ++l) anchored[l] = P.fixedMask[lp.globalId[l]] != 0;
  TVector owned(ownedAll_), ghosted(overlapAll_);
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
    {
      auto od = owned.getDataNonConst();
      for (int i = 0; i < lp.numOwned; ++i)
        for (int c = 0; c < D; ++c) od[i * D + c] = anchored[i];
    }
    ghosted.doImport(owned, *allImport_, Tpetra::INSERT);
    auto gd = ghosted.getData();
    for (int l = lp.numOwned; l < lp.size(); ++l) anchored[l] = anchored[l] || gd[l * D] > 0.5;
  }
  std::vector<long long> loose;
  for (int i = 0; i < lp.numOwned; ++i)
    if (!anchored[i] && !model_->detached(i)) loose.push_back(lp.globalId[i]);
  return onAnyRank(loose);
}

std::vector<long long> PeridynamicEvaluator::onAnyRank(const std::vector<long long>& mine) const {
  const long long n = problem_->disc.size();
  std::vector<int> flag(n, 0), all(n, 0);
  for (long long g : mine) flag[g] = 1;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, static_cast<int>(n), flag.data(), all.data());
  std::vector<long long> ids;
  for (long long g = 0; g < n; ++g)
    if (all[g]) ids.push_back(g);
  return ids;
}

Eigen::Matrix3d PeridynamicEvaluator::rotationMatrix() const {
  const RotationSpec& r = problem_->rotation;
  if (r.angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(lambda_ * r.angle, r.axis).toRotationMatrix();
}

double PeridynamicEvaluator::externalForceNorm() const { return std::abs(lambda_) * fextNorm_; }

double PeridynamicEvaluator::reactionNormOf(const TVector& fint) const {
  auto rd = fint.getData();
  const int D = problem_->dim();
  double s = 0;
  for (int l = 0; l < model_->particles().numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] < 0) s += rd[l * D + c] * rd[l * D + c];
  double g = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, s, Teuchos::outArg(g));
  return std::sqrt(g);
}

double PeridynamicEvaluator::reactionNorm(const Thyra::VectorBase<double>& x) const {
  if (!reactionX_.is_null() && reactionLambda_ == lambda_) {
    // Every rank must take the same branch (the other one is collective).
    auto a = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
    auto b = TOE::getConstTpetraVector(reactionX_.getConst())->getData();
    int same = a.size() == b.size() ? 1 : 0;
    for (decltype(a.size()) k = 0; same && k < a.size(); ++k) same = a[k] == b[k];
    int all = 0;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MIN, same, Teuchos::outArg(all));
    if (all) return reactionNorm_;
  }
  return reactionNormOf(*internalForce(x, nullptr));
}

std::vector<double> PeridynamicEvaluator::reactionOn(const Thyra::VectorBase<double>& x,
                                                     const std::vector<int>& particles) const {
  auto fint = internalForce(x, nullptr);
  auto rd = fint->getData();
  const int D = problem_->dim();
  std::vector<double> s(D, 0.0), g(D, 0.0);
  for (int p : particles)
    if (p >= begin_ && p < end_)
      for (int c = 0; c < D; ++c)
        if (problem_->isFixed(p, c)) s[c] += rd[(p - begin_) * D + c];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, D, s.data(), g.data());
  return g;
}

std::vector<double> PeridynamicEvaluator::ownedDisplacements(const Thyra::VectorBase<double>& x) const {
  auto u = localDisplacements(x);
  u.resize(static_cast<std::size_t>(model_->particles().numOwned) * problem_->dim());
  return u;
}

std::vector<ParticleOutput> PeridynamicEvaluator::ownedOutputs(const Thyra::VectorBase<double>& x) const {
  return model_->outputs(localDisplacements(x));
}

}  // namespace perinox

namespace perinox {

int PeridynamicEvaluator::negativePivots(const Thyra::VectorBase<double>& x) const {
  auto W = assembledJacobian(x, false);
  // Gather every row on rank 0.
  std::vector<GO> mine;
  if (comm_->getRank() == 0)
    for (long long g = 0; g < numFree_; ++g) mine.push_back(g);
  auto rootMap = Teuchos::rcp(new TMap(numFree_, Teuchos::ArrayView<const GO>(mine), 0, comm_));
  Tpetra::Import<LO, GO> imp(ownedFree_, rootMap);
  TCrsMatrix G(rootMap, 0);
  G.doImport(*W, imp, Tpetra::INSERT);
  G.fillComplete(rootMap, rootMap);
  int result = 0;
  if (comm_->getRank() == 0) {
    std::vector<Eigen::Triplet<double>> t;
    const auto n = static_cast<long long>(numFree_);
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
  Teuchos::broadcast(*comm_, 0, Teuchos::outArg(result));
  return result;
}

}  // namespace perinox
