#include "perinox/evaluator/PeridynamicEvaluator.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <limits>
#include <cmath>
#include <sstream>

#include "perinox/model/Partition.hpp"

namespace perinox {

using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;
using MEB = Thyra::ModelEvaluatorBase;

namespace {

/// Sums element contributions into the rank's overlapping residual and matrix.
class TpetraSink final : public ElementSink {
 public:
  TpetraSink(int dim, double* r, const std::vector<int>& freeLid, TCrsMatrix* K)
      : D_(dim), r_(r), freeLid_(freeLid), K_(K) {}

  void add(const int* parts, int n, const double* re, const double* Ke) override {
    const int nd = n * D_;
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < D_; ++c) r_[parts[a] * D_ + c] += re[a * D_ + c];
    if (!Ke || !K_) return;
    cols_.clear();
    pos_.clear();
    for (int b = 0; b < n; ++b)
      for (int e = 0; e < D_; ++e) {
        const int lid = freeLid_[parts[b] * D_ + e];
        if (lid >= 0) {
          cols_.push_back(lid);
          pos_.push_back(b * D_ + e);
        }
      }
    vals_.resize(cols_.size());
    for (int a = 0; a < n; ++a)
      for (int c = 0; c < D_; ++c) {
        const int row = freeLid_[parts[a] * D_ + c];
        if (row < 0) continue;
        const double* Krow = Ke + static_cast<std::size_t>(a * D_ + c) * nd;
        for (std::size_t q = 0; q < cols_.size(); ++q) vals_[q] = Krow[pos_[q]];
        K_->sumIntoLocalValues(row, static_cast<LO>(cols_.size()), vals_.data(), cols_.data());
      }
  }

 private:
  int D_;
  double* r_;
  const std::vector<int>& freeLid_;
  TCrsMatrix* K_;
  std::vector<LO> cols_;
  std::vector<int> pos_;
  std::vector<double> vals_;
};

}  // namespace

PeridynamicEvaluator::PeridynamicEvaluator(Teuchos::RCP<const Teuchos::Comm<int>> comm,
                                           std::shared_ptr<const ProblemSpec> problem)
    : comm_(comm), problem_(std::move(problem)) {
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
  MEB::InArgsSetup<double> in;
  in.setModelEvalDescription("perinox peridynamics");
  in.setSupports(MEB::IN_ARG_x);
  nominal_ = in;
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
  freeExport_ = Teuchos::rcp(new Tpetra::Export<LO, GO>(overlapFree_, ownedFree_));

  // Overlapping graph: every owned element {i} u H_i couples all its particles.
  std::vector<std::vector<int>> adj(nLocal);
  for (int i = 0; i < lp.numOwned; ++i) {
    std::vector<int> parts{i};
    for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) parts.push_back(lp.famIndex[q]);
    for (int a : parts) adj[a].insert(adj[a].end(), parts.begin(), parts.end());
  }
  std::vector<size_t> nnzOv(overlapFreeG.size(), 0);
  for (int l = 0; l < nLocal; ++l) {
    auto& v = adj[l];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    size_t cnt = 0;
    for (int q : v)
      for (int c = 0; c < D; ++c) cnt += overlapFreeLid_[q * D + c] >= 0;
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] >= 0) nnzOv[overlapFreeLid_[l * D + c]] = cnt;
  }
  overlapGraph_ = Teuchos::rcp(new TCrsGraph(overlapFree_, overlapFree_, Teuchos::ArrayView<const size_t>(nnzOv)));
  std::vector<LO> cols;
  for (int l = 0; l < nLocal; ++l) {
    cols.clear();
    for (int q : adj[l])
      for (int c = 0; c < D; ++c)
        if (overlapFreeLid_[q * D + c] >= 0) cols.push_back(overlapFreeLid_[q * D + c]);
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] >= 0)
        overlapGraph_->insertLocalIndices(overlapFreeLid_[l * D + c], Teuchos::ArrayView<const LO>(cols));
  }
  overlapGraph_->fillComplete(ownedFree_, ownedFree_);

  // Owned graph, computed from the replicated families: row particle p couples to every
  // particle of every element that contains p, i.e. of {i} u H_i for i in {p} u H_p.
  std::vector<size_t> nnz;
  std::vector<std::vector<GO>> rowCols;
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
      for (int c = 0; c < D; ++c)
        if (freeId_[s * D + c] >= 0) gc.push_back(freeId_[s * D + c]);
    for (int c = 0; c < D; ++c)
      if (freeId_[p * D + c] >= 0) {
        nnz.push_back(gc.size());
        rowCols.push_back(gc);
      }
  }
  ownedGraph_ = Teuchos::rcp(new TCrsGraph(ownedFree_, Teuchos::ArrayView<const size_t>(nnz)));
  for (size_t r = 0; r < rowCols.size(); ++r)
    ownedGraph_->insertGlobalIndices(ownedFreeG[r], Teuchos::ArrayView<const GO>(rowCols[r]));
  ownedGraph_->fillComplete(ownedFree_, ownedFree_);
  overlapMatrix_ = Teuchos::rcp(new TCrsMatrix(overlapGraph_));
  overlapMatrix_->fillComplete();

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
}

MEB::InArgs<double> PeridynamicEvaluator::getNominalValues() const { return nominal_; }

MEB::InArgs<double> PeridynamicEvaluator::createInArgs() const {
  MEB::InArgsSetup<double> in;
  in.setModelEvalDescription("perinox peridynamics");
  in.setSupports(MEB::IN_ARG_x);
  return in;
}

MEB::OutArgs<double> PeridynamicEvaluator::createOutArgsImpl() const {
  MEB::OutArgsSetup<double> out;
  out.setModelEvalDescription("perinox peridynamics");
  out.setSupports(MEB::OUT_ARG_f);
  out.setSupports(MEB::OUT_ARG_W_op);
  return out;
}

Teuchos::RCP<Thyra::LinearOpBase<double>> PeridynamicEvaluator::create_W_op() const {
  auto A = Teuchos::rcp(new TCrsMatrix(ownedGraph_));
  A->fillComplete();
  return Thyra::createLinearOp<double, LO, GO, Node>(
      Teuchos::rcp_implicit_cast<Tpetra::Operator<double, LO, GO, Node>>(A), xSpace_, xSpace_);
}

std::vector<double> PeridynamicEvaluator::localDisplacements(const Thyra::VectorBase<double>& x) const {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  auto xt = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x));
  auto xd = xt->getData();
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
        } else {
          ud[l * D + c] = lambda_ * P.prescribed[g * D + c];
        }
      }
  }
  TVector uOv(overlapAll_);
  uOv.doImport(uOwned, *allImport_, Tpetra::INSERT);
  auto od = uOv.getData();
  return std::vector<double>(od.begin(), od.end());
}

Teuchos::RCP<TVector> PeridynamicEvaluator::internalForce(const Thyra::VectorBase<double>& x,
                                                           TCrsMatrix* W) const {
  const std::vector<double> u = localDisplacements(x);
  TVector rOv(overlapAll_);
  rOv.putScalar(0.0);
  if (W) {
    overlapMatrix_->resumeFill();
    overlapMatrix_->setAllToScalar(0.0);
  }
  // An EvaluationError on one rank must reach all ranks, or the others hang in the Export.
  int failed = 0;
  std::string message;
  long long particle = -1;
  {
    auto rd = rOv.getDataNonConst();
    TpetraSink sink(problem_->dim(), rd.getRawPtr(), overlapFreeLid_, W ? overlapMatrix_.get() : nullptr);
    try {
      model_->evaluate(u, sink, W != nullptr);
    } catch (const EvaluationError& e) {
      failed = 1;
      message = e.what();
      particle = e.particle();
    }
  }
  int anyFailed = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, failed, Teuchos::outArg(anyFailed));
  if (anyFailed) {
    if (W) overlapMatrix_->fillComplete();
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
  auto r = Teuchos::rcp(new TVector(ownedAll_));
  r->doExport(rOv, *allExport_, Tpetra::ADD);
  if (W) {
    overlapMatrix_->fillComplete();
    W->resumeFill();
    W->setAllToScalar(0.0);
    W->doExport(*overlapMatrix_, *freeExport_, Tpetra::ADD);
    for (const auto& [lid, value] : frozen_) {
      (void)value;
      const LO col = W->getColMap()->getLocalElement(ownedFree_->getGlobalElement(lid));
      W->sumIntoLocalValues(lid, 1, &frozenStiffness_, &col);
    }
    W->fillComplete(ownedFree_, ownedFree_);
  }
  return r;
}

void PeridynamicEvaluator::evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const {
  const auto x = in.get_x();
  const auto f = out.get_f();
  const auto Wop = out.get_W_op();
  if (f.is_null() && Wop.is_null()) return;
  TCrsMatrix* W = nullptr;
  if (!Wop.is_null()) {
    auto op = TOE::getTpetraOperator(Wop);
    W = &dynamic_cast<TCrsMatrix&>(*op);
  }
  auto fint = internalForce(*x, W);
  if (!f.is_null()) {
    auto ft = TOE::getTpetraVector(f);
    auto fd = ft->getDataNonConst();
    auto rd = fint->getData();
    auto fe = fextOwnedFree_->getData();
    const int D = problem_->dim();
    LO k = 0;
    const LocalParticles& lp = model_->particles();
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c)
        if (overlapFreeLid_[l * D + c] >= 0) {
          fd[k] = rd[l * D + c] - lambda_ * fe[k];
          ++k;
        }
    if (!frozen_.empty()) {
      auto xd = TOE::getConstTpetraVector(x)->getData();
      for (const auto& [lid, value] : frozen_) fd[lid] = frozenStiffness_ * (xd[lid] - value);
    }
  }
}

PeridynamicEvaluator::BreakReport PeridynamicEvaluator::breakBonds(const Thyra::VectorBase<double>& x) {
  BreakReport rep;
  const auto u = localDisplacements(x);
  long long local = model_->breakBonds(u);
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, local, Teuchos::outArg(rep.brokenBonds));
  const int D = problem_->dim();
  const long long n = problem_->disc.size();
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  for (int round = 0; round < 1000; ++round) {
    // Flags of every particle that became singular on any rank (rare: after damage only).
    std::vector<int> mine(n, 0), all(n, 0);
    for (long long g : model_->singularParticles()) mine[g] = 1;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, static_cast<int>(n), mine.data(), all.data());
    std::vector<long long> ids;
    for (long long g = 0; g < n; ++g)
      if (all[g]) ids.push_back(g);
    if (ids.empty()) break;
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
  }
  std::sort(detachedAll_.begin(), detachedAll_.end());
  return rep;
}

double PeridynamicEvaluator::externalForceNorm() const { return std::abs(lambda_) * fextOwnedFree_->norm2(); }

double PeridynamicEvaluator::reactionNorm(const Thyra::VectorBase<double>& x) const {
  auto fint = internalForce(x, nullptr);
  auto rd = fint->getData();
  const int D = problem_->dim();
  double s = 0;
  for (int l = 0; l < model_->particles().numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (overlapFreeLid_[l * D + c] < 0) s += rd[l * D + c] * rd[l * D + c];
  double g = 0;
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, s, Teuchos::outArg(g));
  return std::sqrt(g);
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
  auto Wop = create_W_op();
  auto in = createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto out = createOutArgs();
  out.set_W_op(Wop);
  evalModel(in, out);
  auto W = Teuchos::rcp_dynamic_cast<const TCrsMatrix>(TOE::getConstTpetraOperator(Wop), true);
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
