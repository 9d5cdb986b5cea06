// The two-stage preconditioner (see the header): Ifpack2 smoother on J, MueLu V-cycle of the
// auxiliary matrix. MueLu and Ifpack2 headers are heavy: this is their only user besides
// LinearSolver.cpp.
#include "perinox/solver/TwoStagePreconditioner.hpp"

#include "perinox/evaluator/OperatorDiagonal.hpp"

#include <Ifpack2_Factory.hpp>
#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <MueLu_Level.hpp>
#include <MueLu_MasterList.hpp>
#include <Xpetra_Import.hpp>
#include <Xpetra_MultiVectorFactory.hpp>
#include <Xpetra_TpetraMultiVector.hpp>
#include <Thyra_DefaultPreconditioner.hpp>
#include <Thyra_TpetraLinearOp.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Vector.hpp>

#include <cmath>
#include <stdexcept>

namespace perinox {

namespace {
using LO = int;
using GO = long long;
using Node = Tpetra::Map<LO, GO>::node_type;
using TMap = Tpetra::Map<LO, GO, Node>;
using MV = Tpetra::MultiVector<double, LO, GO, Node>;
using OP = Tpetra::Operator<double, LO, GO, Node>;
using TCrsMatrix = Tpetra::CrsMatrix<double, LO, GO, Node>;
using RowMatrix = Tpetra::RowMatrix<double, LO, GO, Node>;
using Teuchos::RCP;
using Teuchos::rcp;

/// An operator on the all-DOF map seen on J's free DOFs: y_free = (M [x_free; 0])_free.
class FreeRestriction final : public OP {
 public:
  FreeRestriction(RCP<const OP> inner, RCP<const TMap> freeMap, std::vector<LO> freeToAll)
      : inner_(std::move(inner)), free_(std::move(freeMap)), freeToAll_(std::move(freeToAll)) {}
  RCP<const TMap> getDomainMap() const override { return free_; }
  RCP<const TMap> getRangeMap() const override { return free_; }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    const size_t nv = X.getNumVectors();
    if (xa_.is_null() || xa_->getNumVectors() != nv) {
      xa_ = rcp(new MV(inner_->getDomainMap(), nv));
      ya_ = rcp(new MV(inner_->getRangeMap(), nv));
    }
    xa_->putScalar(0.0);
    for (size_t v = 0; v < nv; ++v) {
      auto x = X.getData(v);
      auto xa = xa_->getDataNonConst(v);
      for (size_t k = 0; k < freeToAll_.size(); ++k) xa[freeToAll_[k]] = x[k];
    }
    inner_->apply(*xa_, *ya_, mode, 1.0, 0.0);
    for (size_t v = 0; v < nv; ++v) {
      auto ya = ya_->getData(v);
      auto y = Y.getDataNonConst(v);
      for (size_t k = 0; k < freeToAll_.size(); ++k)
        y[k] = (beta == 0.0 ? 0.0 : beta * y[k]) + alpha * ya[freeToAll_[k]];
    }
  }

 private:
  RCP<const OP> inner_;
  RCP<const TMap> free_;
  std::vector<LO> freeToAll_;
  mutable RCP<MV> xa_, ya_;
};

/// MueLu's V-cycle from a zero guess, entered at level 1 when the finest level has no smoother:
/// there the finest level's residual is the right-hand side itself, which MueLu's own apply
/// computes anyway as B - A 0, a product with the widest matrix of the hierarchy (on Peridigm's
/// tensile test 18 % of the run: docs/performance.md, "The auxiliary cycle from level 1, and the last Newton system"). Restrict, move to the
/// repartitioned level 1 when MueLu would (an "Importer" there and P and R not rebalanced),
/// cycle from level 1, move back, prolongate: the same arithmetic as MueLu's (B - A 0 = B and
/// 0 + P x = P x exactly).
class CoarseEntryCycle final : public OP {
 public:
  using Hierarchy = MueLu::Hierarchy<double, LO, GO, Node>;
  using XMV = Xpetra::MultiVector<double, LO, GO, Node>;
  using XTMV = Xpetra::TpetraMultiVector<double, LO, GO, Node>;
  using XOp = Xpetra::Operator<double, LO, GO, Node>;
  using XImport = Xpetra::Import<LO, GO, Node>;

  CoarseEntryCycle(RCP<MueLu::TpetraOperator<double, LO, GO, Node>> muelu, bool transfersRebalanced)
      : muelu_(std::move(muelu)) {
    auto H = muelu_->GetHierarchy();
    auto L1 = H->GetLevel(1);
    P_ = L1->IsAvailable("Pbar") ? L1->Get<RCP<XOp>>("Pbar") : L1->Get<RCP<XOp>>("P");
    if (!H->GetImplicitTranspose()) R_ = L1->Get<RCP<XOp>>("R");
    Ac_ = L1->Get<RCP<XOp>>("A");
    if (!transfersRebalanced && L1->IsAvailable("Importer")) importer_ = L1->Get<RCP<const XImport>>("Importer");
  }
  /// Whether the hierarchy's cycle may be entered at level 1: more than one level and no
  /// smoother on level 0.
  static bool applies(const MueLu::TpetraOperator<double, LO, GO, Node>& muelu) {
    auto H = muelu.GetHierarchy();
    if (H.is_null() || H->GetNumLevels() < 2) return false;
    auto L0 = H->GetLevel(0), L1 = H->GetLevel(1);
    return !L0->IsAvailable("PreSmoother") && !L0->IsAvailable("PostSmoother") && L1->IsAvailable("P") &&
           L1->IsAvailable("A") && (H->GetImplicitTranspose() || L1->IsAvailable("R"));
  }
  RCP<const TMap> getDomainMap() const override { return muelu_->getDomainMap(); }
  RCP<const TMap> getRangeMap() const override { return muelu_->getRangeMap(); }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    if (mode != Teuchos::NO_TRANS) throw std::logic_error("the auxiliary V-cycle has no transpose");
    const size_t nv = X.getNumVectors();
    if (rhs_.is_null() || rhs_->getNumVectors() != nv) {
      using Factory = Xpetra::MultiVectorFactory<double, LO, GO, Node>;
      rhs_ = Factory::Build(R_.is_null() ? P_->getDomainMap() : R_->getRangeMap(), nv);
      cx_ = Factory::Build(P_->getDomainMap(), nv);
      if (!importer_.is_null()) {
        rhsMoved_ = Factory::Build(importer_->getTargetMap(), nv);
        cxMoved_ = Factory::Build(importer_->getTargetMap(), nv);
      }
    }
    const XTMV x(Teuchos::rcpFromRef(const_cast<MV&>(X)));
    XTMV y(Teuchos::rcpFromRef(Y));
    if (R_.is_null())
      P_->apply(x, *rhs_, Teuchos::TRANS, 1.0, 0.0);
    else
      R_->apply(x, *rhs_, Teuchos::NO_TRANS, 1.0, 0.0);
    RCP<XMV> rhs = rhs_, cx = cx_;
    if (!importer_.is_null()) {
      rhsMoved_->doImport(*rhs_, *importer_, Xpetra::INSERT);
      rhs = rhsMoved_;
      cx = cxMoved_;
    }
    cx->putScalar(0.0);
    if (!Ac_.is_null()) {  // null on a rank that holds nothing of the repartitioned level
      const auto xMap = cx->getMap(), rMap = rhs->getMap();
      rhs->replaceMap(Ac_->getRangeMap());
      cx->replaceMap(Ac_->getDomainMap());
      muelu_->GetHierarchy()->Iterate(*rhs, *cx, 1, true, 1);
      cx->replaceMap(xMap);
      rhs->replaceMap(rMap);
    }
    if (!importer_.is_null()) cx_->doExport(*cxMoved_, *importer_, Xpetra::INSERT);
    P_->apply(*cx_, y, Teuchos::NO_TRANS, alpha, beta);
  }

 private:
  RCP<MueLu::TpetraOperator<double, LO, GO, Node>> muelu_;
  RCP<XOp> P_, R_, Ac_;
  RCP<const XImport> importer_;
  mutable RCP<XMV> rhs_, cx_, rhsMoved_, cxMoved_;
};

/// y = S r; y += V (r - J y); y += S (r - J y)   (S and V applied with a zero initial guess).
class TwoStageOperator final : public OP {
 public:
  TwoStageOperator(RCP<const OP> J, RCP<const OP> S, RCP<const OP> V)
      : J_(std::move(J)), S_(std::move(S)), V_(std::move(V)) {}
  RCP<const TMap> getDomainMap() const override { return J_->getDomainMap(); }
  RCP<const TMap> getRangeMap() const override { return J_->getRangeMap(); }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    const size_t nv = X.getNumVectors();
    if (y_.is_null() || y_->getNumVectors() != nv) {
      y_ = rcp(new MV(X.getMap(), nv));
      r_ = rcp(new MV(X.getMap(), nv));
      d_ = rcp(new MV(X.getMap(), nv));
    }
    S_->apply(X, *y_, mode);
    J_->apply(*y_, *r_, mode);
    r_->update(1.0, X, -1.0);
    V_->apply(*r_, *d_, mode);
    y_->update(1.0, *d_, 1.0);
    J_->apply(*y_, *r_, mode);
    r_->update(1.0, X, -1.0);
    S_->apply(*r_, *d_, mode);
    y_->update(1.0, *d_, 1.0);
    Y.update(alpha, *y_, beta);
  }

 private:
  RCP<const OP> J_, S_, V_;
  mutable RCP<MV> y_, r_, d_;
};

/// Chebyshev smoothing of J y = r with diagonal scaling D, from y = 0, over the interval
/// [lambda_max / ratio, lambda_max] of D^-1 J: `degree` polynomial steps, degree - 1 products
/// with J. J is any operator (the matrix-free Jacobian); D^-1 and lambda_max are given
/// (operatorSmoother: J's own diagonal or the auxiliary matrix's, and powerIteration).
class OperatorChebyshev final : public OP {
 public:
  OperatorChebyshev(RCP<const OP> J, RCP<const MV> inverseDiagonal, int degree, double lambdaMax, double ratio)
      : J_(std::move(J)), dinv_(std::move(inverseDiagonal)), degree_(degree), lmax_(lambdaMax), ratio_(ratio) {}
  RCP<const TMap> getDomainMap() const override { return J_->getDomainMap(); }
  RCP<const TMap> getRangeMap() const override { return J_->getRangeMap(); }
  void apply(const MV& X, MV& Y, Teuchos::ETransp, double alpha, double beta) const override {
    const size_t nv = X.getNumVectors();
    if (y_.is_null() || y_->getNumVectors() != nv) {
      y_ = rcp(new MV(X.getMap(), nv));
      d_ = rcp(new MV(X.getMap(), nv));
      w_ = rcp(new MV(X.getMap(), nv));
    }
    const double lmin = lmax_ / ratio_, theta = 0.5 * (lmax_ + lmin), delta = 0.5 * (lmax_ - lmin);
    const double sigma = theta / delta;
    double rho = 1.0 / sigma;
    // d = D^-1 r / theta; y = d
    for (size_t v = 0; v < nv; ++v) d_->getVectorNonConst(v)->elementWiseMultiply(1.0 / theta, *dinv_->getVector(0),
                                                                                   *X.getVector(v), 0.0);
    Tpetra::deep_copy(*y_, *d_);
    for (int k = 1; k < degree_; ++k) {
      const double rhoNew = 1.0 / (2.0 * sigma - rho);
      J_->apply(*y_, *w_);
      w_->update(1.0, X, -1.0);  // w = r - J y
      for (size_t v = 0; v < nv; ++v)
        d_->getVectorNonConst(v)->elementWiseMultiply(2.0 * rhoNew / delta, *dinv_->getVector(0), *w_->getVector(v),
                                                      rhoNew * rho);
      y_->update(1.0, *d_, 1.0);
      rho = rhoNew;
    }
    Y.update(alpha, *y_, beta);
  }

 private:
  RCP<const OP> J_;
  RCP<const MV> dinv_;
  int degree_;
  double lmax_, ratio_;
  mutable RCP<MV> y_, d_, w_;
};

/// The largest eigenvalue of D^-1 J by the power method from x (updated to the last iterate, so
/// the next set-up starts there), `iterations` products with J; the estimate is Ifpack2's,
/// (x, D^-1 J x) / (x, x) with x of unit length.
double powerIteration(const OP& J, const MV& dinv, MV& x, int iterations) {
  MV y(x.getMap(), 1);
  double lambda = 0.0;
  x.scale(1.0 / x.getVector(0)->norm2());
  for (int k = 0; k < iterations; ++k) {
    J.apply(x, y);
    y.getVectorNonConst(0)->elementWiseMultiply(1.0, *dinv.getVector(0), *y.getVector(0), 0.0);
    lambda = x.getVector(0)->dot(*y.getVector(0));
    const double n = y.getVector(0)->norm2();
    if (!(n > 0) || !std::isfinite(n)) break;
    x.update(1.0 / n, y, 0.0);
  }
  return lambda;
}

Teuchos::ParameterList defaultMueLu() {
  Teuchos::ParameterList p("MueLu");
  p.set("verbosity", "none");
  p.set("multigrid algorithm", "sa");
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

class TwoStageFactory final : public Thyra::PreconditionerFactoryBase<double> {
 public:
  explicit TwoStageFactory(std::shared_ptr<AuxiliarySource> source) : source_(std::move(source)) {}

  bool isCompatible(const Thyra::LinearOpSourceBase<double>& src) const override {
    return !tpetraOf(src.getOp()).is_null();
  }
  RCP<Thyra::PreconditionerBase<double>> createPrec() const override {
    return rcp(new Thyra::DefaultPreconditioner<double>);
  }
  void initializePrec(const RCP<const Thyra::LinearOpSourceBase<double>>& src, Thyra::PreconditionerBase<double>* prec,
                      const Thyra::ESupportSolveUse) const override {
    // J: the assembled Jacobian (Ifpack2 smoother on it), or the matrix-free Jacobian operator
    // (perinox's Chebyshev on it: operatorSmoother).
    auto Jop = tpetraOf(src->getOp());
    if (Jop.is_null())
      throw std::invalid_argument(
          "the Two-Stage preconditioner needs a Tpetra operator: the assembled Jacobian, or the matrix-free one "
          "(Solver/Jacobian = Matrix-Free with Preconditioner Matrix = None)");
    auto J = Teuchos::rcp_dynamic_cast<const TCrsMatrix>(Jop);
    if (!source_)
      throw std::invalid_argument(
          "the Two-Stage preconditioner has no auxiliary operator: build the linear solver with "
          "perinox::buildLinearSolverFactory(params, ranks, makeAuxiliarySource(evaluator, params))");
    const Teuchos::ParameterList& pl = *parameters();
    ++stats_.setups;
    const AuxiliaryOperator& aux = source_->current();
    const RCP<const TMap> rows = Jop->getRangeMap();
    if (aux.matrix.is_null() || aux.freeToAll.size() != rows->getNodeNumElements())
      throw std::logic_error("the Two-Stage preconditioner's auxiliary operator does not match the Jacobian's rows");
    if (hierarchy_.is_null() || version_ != aux.version || auxMatrix_.get() != aux.matrix.get()) {
      Teuchos::ParameterList mp = pl.sublist("MueLu");
      mp.set("number of equations", aux.blockSize);
      // The finest level is smoothed by the Chebyshev steps on J; the auxiliary matrix's own
      // sweeps there cost 12-36 % of a solve for no fewer Krylov iterations on undamaged bodies,
      // but save a third of them on damaged ones (docs/performance.md, "The auxiliary hierarchy's finest level"). A "level 0"
      // list of the user's MueLu parameters is left as given.
      const std::string fine = pl.get<std::string>("Auxiliary Fine Smoothing");
      if ((fine == "Never" || (fine == "Auto" && !aux.damage)) && !mp.isSublist("level 0"))
        mp.sublist("level 0").set("smoother: pre or post", "none");
      auto& user = mp.sublist("user data");
      user.set("Nullspace", Teuchos::rcp_const_cast<MV>(aux.nullspace));
      user.set("Coordinates", Teuchos::rcp_const_cast<MV>(aux.coordinates));
      // On more than one rank the coarse level is gathered onto one rank: MueLu's coarse KLU2
      // solves a distributed coarse matrix wrongly in this build without saying so
      // (docs/trilinos-notes.md); the default start level (2) leaves a two-level hierarchy's
      // coarse level distributed.
      if (rows->getComm()->getSize() > 1 && !mp.isParameter("repartition: enable")) {
        mp.set("repartition: enable", true);
        mp.set("repartition: min rows per proc", 4000);
        mp.set("repartition: start level", 1);
        mp.set("repartition: partitioner", "zoltan2");
        mp.sublist("repartition: params").set("algorithm", "multijagged");
      }
      RCP<OP> A = Teuchos::rcp_const_cast<TCrsMatrix>(aux.matrix);
      hierarchy_ = MueLu::CreateTpetraPreconditioner<double, LO, GO, Node>(A, mp);
      const auto H = hierarchy_->GetHierarchy();
      stats_.levels = H->GetNumLevels();
      if (stats_.levels > 1) {  // a one-level hierarchy is its coarse solve
        const auto L0 = H->GetLevel(0);
        if (L0->IsAvailable("PreSmoother") || L0->IsAvailable("PostSmoother")) ++stats_.fineSmoothedHierarchies;
      }
      ++stats_.hierarchiesBuilt;
      version_ = aux.version;
      auxMatrix_ = aux.matrix;
      const RCP<const OP> cycle = auxiliaryCycle(hierarchy_, mp);
      if (cycle.get() != hierarchy_.get()) ++stats_.coarseEntryHierarchies;
      coarse_ = rcp(new FreeRestriction(cycle, rows, aux.freeToAll));
      dinv_ = Teuchos::null;  // the diagonal scaling of the operator smoother follows the auxiliary matrix
    }
    RCP<const OP> S;
    if (!J.is_null()) {
      auto smoother = Ifpack2::Factory::create<RowMatrix>(pl.get<std::string>("Fine Smoother"), J);
      smoother->setParameters(pl.sublist("Fine Smoother Parameters"));
      smoother->initialize();
      smoother->compute();
      S = smoother;
    } else {
      S = operatorSmoother(Jop, aux, pl);
    }
    RCP<OP> M = rcp(new TwoStageOperator(Jop, S, coarse_));
    auto space = Thyra::tpetraVectorSpace<double, LO, GO, Node>(rows);
    Teuchos::RCP<const Thyra::LinearOpBase<double>> thyraM = Thyra::tpetraLinearOp<double, LO, GO, Node>(space, space, M);
    auto* def = dynamic_cast<Thyra::DefaultPreconditioner<double>*>(prec);
    if (def == nullptr) throw std::logic_error("the Two-Stage preconditioner needs a Thyra::DefaultPreconditioner");
    def->initializeUnspecified(thyraM);
    source_src_ = src.create_weak();  // a weak reference: the factory must not keep the operator (and its matrix) alive
  }
  void uninitializePrec(Thyra::PreconditionerBase<double>* prec, RCP<const Thyra::LinearOpSourceBase<double>>* src,
                        Thyra::ESupportSolveUse* use) const override {
    if (src) *src = source_src_.is_valid_ptr() ? source_src_.create_strong() : Teuchos::null;
    if (use) *use = Thyra::SUPPORT_SOLVE_UNSPECIFIED;
    if (auto* def = dynamic_cast<Thyra::DefaultPreconditioner<double>*>(prec)) def->uninitialize();
  }

  void setParameterList(const RCP<Teuchos::ParameterList>& pl) override {
    pl->validateParametersAndSetDefaults(*getValidParameters(), 0);
    params_ = pl;
  }
  RCP<Teuchos::ParameterList> getNonconstParameterList() override { return params_; }
  RCP<Teuchos::ParameterList> unsetParameterList() override {
    auto p = params_;
    params_ = Teuchos::null;
    return p;
  }
  RCP<const Teuchos::ParameterList> getParameterList() const override { return params_; }
  RCP<const Teuchos::ParameterList> getValidParameters() const override { return twoStageValidParameters(); }
  std::string description() const override { return "perinox Two-Stage preconditioner"; }

  const TwoStageStatistics& statistics() const { return stats_; }

 private:
  static RCP<const OP> tpetraOf(const RCP<const Thyra::LinearOpBase<double>>& op) {
    using ThyraOp = Thyra::TpetraLinearOp<double, LO, GO, Node>;
    auto t = Teuchos::rcp_dynamic_cast<const ThyraOp>(op);
    if (t.is_null()) return Teuchos::null;
    return t->getConstTpetraOperator();
  }

  /// The smoother on an operator J (no matrix): Chebyshev over D^-1 J with D J's own diagonal
  /// when J gives it (OperatorDiagonal), else the auxiliary matrix's diagonal on J's rows (the
  /// same elasticity on the same particles: the same local stiffness up to a factor, which costs
  /// Krylov iterations: 47 against 26 per solve on a 1 000-particle 3D block); lambda_max by the
  /// power method, warm-started from the previous set-up's iterate.
  RCP<const OP> operatorSmoother(const RCP<const OP>& J, const AuxiliaryOperator& aux,
                                 const Teuchos::ParameterList& pl) const {
    if (pl.get<std::string>("Fine Smoother") != "CHEBYSHEV")
      throw std::invalid_argument("the Two-Stage preconditioner on a matrix-free Jacobian smooths with its own Chebyshev "
                                  "iteration: 'Fine Smoother' = '" +
                                  pl.get<std::string>("Fine Smoother") + "' needs an assembled matrix");
    const Teuchos::ParameterList& fs = pl.sublist("Fine Smoother Parameters");
    auto number = [&](const char* key, double fallback) {
      if (!fs.isParameter(key)) return fallback;
      if (fs.isType<int>(key)) return static_cast<double>(fs.get<int>(key));
      if (fs.isType<double>(key)) return fs.get<double>(key);
      throw std::invalid_argument(std::string("Two-Stage 'Fine Smoother Parameters': '") + key + "' must be a number");
    };
    const int degree = static_cast<int>(number("chebyshev: degree", 1));
    const double ratio = number("chebyshev: ratio eigenvalue", 30.0);
    const int first = static_cast<int>(number("chebyshev: eigenvalue max iterations", 10));
    const double boost = number("chebyshev: boost factor", 1.1);
    const int warm = pl.get<int>("Warm Eigenvalue Iterations");
    if (degree < 1 || !(ratio > 1) || first < 1 || !(boost >= 1) || warm < 0)
      throw std::invalid_argument(
          "Two-Stage on a matrix-free Jacobian: 'chebyshev: degree' and 'chebyshev: eigenvalue max iterations' must be "
          "at least 1, 'chebyshev: ratio eigenvalue' above 1, 'chebyshev: boost factor' at least 1, 'Warm Eigenvalue "
          "Iterations' at least 0");
    const RCP<const TMap> rows = J->getRangeMap();
    RCP<MV> diagonal;  // a new diagonal on J's rows, inverted below
    if (auto* own = dynamic_cast<const OperatorDiagonal*>(J.get())) {
      // The operator's own diagonal (the matrix-free Jacobian's), at every set-up: it follows
      // the state as an assembled matrix's would.
      diagonal = rcp(new MV(rows, 1));
      own->getDiagonal(*diagonal);
      ++stats_.operatorDiagonals;
    } else if (dinv_.is_null() || !dinv_->getMap()->isSameAs(*rows)) {
      Tpetra::Vector<double, LO, GO, Node> all(aux.matrix->getRowMap());
      aux.matrix->getLocalDiagCopy(all);
      auto ad = all.getData();
      diagonal = rcp(new MV(rows, 1));
      auto dd = diagonal->getDataNonConst(0);
      for (std::size_t k = 0; k < aux.freeToAll.size(); ++k) dd[k] = ad[aux.freeToAll[k]];
    }
    if (!diagonal.is_null()) {
      auto dd = diagonal->getDataNonConst(0);
      for (decltype(dd.size()) k = 0; k < dd.size(); ++k) dd[k] = dd[k] > 0 && std::isfinite(dd[k]) ? 1.0 / dd[k] : 0.0;
      dinv_ = diagonal;
    }
    int iterations = warm;
    if (eigenvector_.is_null() || !eigenvector_->getMap()->isSameAs(*rows)) {
      // A start with components in every mode, the same on any partition: a hash of the global row.
      eigenvector_ = rcp(new MV(rows, 1));
      auto e = eigenvector_->getDataNonConst(0);
      for (decltype(e.size()) k = 0; k < e.size(); ++k) {
        unsigned long long h = static_cast<unsigned long long>(rows->getGlobalElement(static_cast<LO>(k))) + 0x9e3779b97f4a7c15ULL;
        h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
        h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
        h ^= h >> 31;
        e[k] = 0.5 + static_cast<double>(h >> 11) * 0x1.0p-53;
      }
      iterations = first;
      lambdaMax_ = 0.0;
    }
    if (iterations > 0) {
      const double l = powerIteration(*J, *dinv_, *eigenvector_, iterations) * boost;
      if (!(l > 0) || !std::isfinite(l))
        throw std::runtime_error("the Two-Stage preconditioner's Chebyshev smoother found no positive eigenvalue of "
                                 "D^-1 J (the Jacobian is not positive on the power method's vector)");
      lambdaMax_ = l;
      stats_.eigenvalueProducts += iterations;
    }
    return rcp(new OperatorChebyshev(J, dinv_, degree, lambdaMax_, ratio));
  }
  RCP<const Teuchos::ParameterList> parameters() const {
    if (params_.is_null()) {
      auto p = rcp(new Teuchos::ParameterList(*getValidParameters()));
      return p;
    }
    return params_;
  }

  std::shared_ptr<AuxiliarySource> source_;
  RCP<Teuchos::ParameterList> params_;
  mutable RCP<MueLu::TpetraOperator<double, LO, GO, Node>> hierarchy_;
  mutable RCP<const TCrsMatrix> auxMatrix_;
  mutable RCP<const OP> coarse_;
  mutable long long version_ = -1;
  mutable TwoStageStatistics stats_;
  mutable RCP<const Thyra::LinearOpSourceBase<double>> source_src_;
  mutable RCP<const MV> dinv_;
  mutable RCP<MV> eigenvector_;
  mutable double lambdaMax_ = 0.0;
};

}  // namespace

Teuchos::RCP<const Teuchos::ParameterList> twoStageValidParameters() {
  static const RCP<const Teuchos::ParameterList> valid = [] {
    auto p = rcp(new Teuchos::ParameterList(twoStageName()));
    p->set("Fine Smoother", "CHEBYSHEV", "Ifpack2 preconditioner type of the smoother on the Jacobian itself");
    Teuchos::ParameterList fs;
    fs.set("chebyshev: degree", 2);
    fs.set("chebyshev: ratio eigenvalue", 7.0);
    fs.set("chebyshev: zero starting solution", true);
    p->set("Fine Smoother Parameters", fs, "Ifpack2 parameters of the fine smoother");
    p->set("MueLu", defaultMueLu(), "MueLu parameters of the auxiliary matrix's hierarchy ('number of equations', "
                                    "the near-null space and coordinates are set from the auxiliary operator)");
    const Teuchos::Array<std::string> kinds = Teuchos::tuple<std::string>("Auto", "Lattice FEM", "Short Horizon");
    p->set("Auxiliary Operator", "Auto",
           "Lattice FEM (bilinear / trilinear finite-element stiffness on the particle lattice), Short Horizon (the "
           "peridynamic Jacobian of the same body at a horizon of 'Auxiliary Horizon Factor' spacings, bonds broken "
           "as in the body), or Auto (Lattice FEM on an undamaged lattice, Short Horizon otherwise)",
           rcp(new Teuchos::StringValidator(kinds)));
    p->set("Auxiliary Fine Smoothing", "Auto",
           "MueLu's smoother on the auxiliary hierarchy's finest level: Always, Never (the Chebyshev steps on J "
           "smooth there), or Auto (only when the body has damage); a 'level 0' list in MueLu's parameters wins",
           rcp(new Teuchos::StringValidator(Teuchos::tuple<std::string>("Auto", "Always", "Never"))));
    p->set("Warm Eigenvalue Iterations", 3,
           "matrix-free Jacobian: power iterations for the Chebyshev smoother's largest eigenvalue at each set-up after "
           "the first, started from the last set-up's vector (the first takes 'chebyshev: eigenvalue max iterations'); "
           "0 keeps the first estimate");
    p->set("Auxiliary Horizon Factor", 0.0,
           "Short Horizon: horizon / spacing of the auxiliary operator (0: 1.015 on a lattice, 1.6 otherwise)");
    return RCP<const Teuchos::ParameterList>(p);
  }();
  return valid;
}

Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> twoStagePreconditionerFactory(
    std::shared_ptr<AuxiliarySource> source) {
  return rcp(new TwoStageFactory(std::move(source)));
}

Teuchos::RCP<const Tpetra::Operator<double, int, long long>> freeRestriction(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> inner, Teuchos::RCP<const Tpetra::Map<int, long long>> freeMap,
    std::vector<int> freeToAll) {
  return rcp(new FreeRestriction(std::move(inner), std::move(freeMap), std::move(freeToAll)));
}

Teuchos::RCP<const Tpetra::Operator<double, int, long long>> twoStageOperator(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> J, Teuchos::RCP<const Tpetra::Operator<double, int, long long>> S,
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> V) {
  return rcp(new TwoStageOperator(std::move(J), std::move(S), std::move(V)));
}

Teuchos::RCP<const Tpetra::Operator<double, int, long long>> auxiliaryCycle(
    Teuchos::RCP<const Tpetra::Operator<double, int, long long>> hierarchy, const Teuchos::ParameterList& mueluParameters) {
  auto muelu = Teuchos::rcp_dynamic_cast<const MueLu::TpetraOperator<double, LO, GO, Node>>(hierarchy);
  if (muelu.is_null() || !CoarseEntryCycle::applies(*muelu)) return hierarchy;
  const char* key = "repartition: rebalance P and R";
  const bool rebalanced = mueluParameters.isType<bool>(key) ? mueluParameters.get<bool>(key)
                                                             : MueLu::MasterList::getDefault<bool>(key);
  return rcp(new CoarseEntryCycle(Teuchos::rcp_const_cast<MueLu::TpetraOperator<double, LO, GO, Node>>(muelu), rebalanced));
}

TwoStageStatistics twoStageStatistics(const Thyra::PreconditionerFactoryBase<double>& factory) {
  if (auto* f = dynamic_cast<const TwoStageFactory*>(&factory)) return f->statistics();
  return {};
}

}  // namespace perinox
