// The Thyra adapter (see PeridynamicEvaluator.hpp): in/out arguments, the load factor p(0) and
// DfDp, W_op / W_prec, and the diagnostics. The Tpetra work is in Assembly.cpp, the damage state
// in Damage.cpp.
#include "perinox/evaluator/PeridynamicEvaluator.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Thyra_DefaultLinearOpSource.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "perinox/evaluator/JacobianOperators.hpp"
#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/evaluator/Partitioner.hpp"

namespace perinox {

using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;
using MEB = Thyra::ModelEvaluatorBase;

namespace {

/// validateProblem on every rank, and the same exception on every rank when any refuses. A
/// replicated problem is the same everywhere; a distributed one is checked share by share (the
/// lowest refusing rank's sentence is the one thrown), then for rigid-body motion over the ranks.
void validateTogether(const Teuchos::Comm<int>& comm, const ProblemSpec& P) {
  std::string err;
  try {
    validateProblem(P);
  } catch (const std::exception& e) {
    err = e.what();
  }
  if (!P.distributed) {
    if (!err.empty()) throw std::invalid_argument(err);
    return;
  }
  if (err = lowestRankMessage(comm, err); !err.empty()) throw std::invalid_argument(err);
  // A share may miss a block; the body may not (validateProblem's check of a replicated problem).
  if (!P.blocks.empty()) {
    const std::vector<int> of = P.blockIndex();
    std::vector<long long> mine(P.blocks.size(), 0), all(P.blocks.size(), 0);
    for (long long g : P.owned) ++mine[of[P.index(g)]];
    Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, static_cast<int>(mine.size()), mine.data(), all.data());
    for (std::size_t k = 0; k < all.size(); ++k)
      if (all[k] == 0)
        throw std::invalid_argument("ProblemSpec: blocks[" + std::to_string(k) + "] names block " +
                                    std::to_string(P.blocks[k].id) + ", which has no particle");
  }
  if (!preventsRigidMotion(comm, P))
    throw std::invalid_argument(
        "ProblemSpec: the prescribed DOFs (fixedMask) do not prevent rigid-body motion: a translation or rotation of "
        "the whole body is free; prescribe more components");
}

}  // namespace

bool preventsRigidMotion(const Teuchos::Comm<int>& comm, const ProblemSpec& P) {
  if (!P.distributed) return preventsRigidMotion(P);
  const Eigen::MatrixXd mine = rigidModeGram(P);
  Eigen::MatrixXd all(mine.rows(), mine.cols());
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, static_cast<int>(mine.size()), mine.data(), all.data());
  return gramHasFullRank(all);
}

long long prescribedDofCount(const Teuchos::Comm<int>& comm, const ProblemSpec& P) {
  long long mine = 0;
  for (int i = 0; i < P.disc.size(); ++i)
    if (P.owns(P.distributed ? P.globalId[i] : i))
      for (int c = 0; c < P.disc.dim; ++c) mine += (P.fixedMask[i] >> c) & 1u;
  long long all = mine;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(all));
  return all;
}

PeridynamicEvaluator::PeridynamicEvaluator(Teuchos::RCP<const Teuchos::Comm<int>> comm,
                                           std::shared_ptr<const ProblemSpec> problem)
    : comm_(comm), problem_(std::move(problem)) {
  if (!problem_) throw std::invalid_argument("ProblemSpec: the evaluator was given no problem");
  validateTogether(*comm_, *problem_);
  const ProblemSpec& P = *problem_;
  // Each rank's families and model are its own work: a refusal there (a particle whose family
  // does not span the space, coincident particles) is agreed by all ranks before any collective.
  owned_ = P.distributed ? P.owned : perinox::ownedParticles(comm_, P.disc, P.partition);  // collective
  agreeOnSetUp(*comm_, [&] { buildModel(); });
  dofs_ = DofMaps(comm_, P, model_->particles());
  assembler_ = std::make_unique<Assembler>(comm_, P, *model_, dofs_, families_);
  damage_ = std::make_unique<DamageBookkeeping>(comm_, P, *model_, dofs_, families_);
  buildExternalForce();
  computeRoundoffScale();
  {  // every rank takes the same branch in loadDerivative (a distributed share may prescribe none)
    int mine = P.prescribesDisplacement() ? 1 : 0, any = 0;
    Teuchos::reduceAll(*comm_, Teuchos::REDUCE_MAX, mine, Teuchos::outArg(any));
    prescribesDisplacement_ = any != 0;
  }
  xSpace_ = Thyra::createVectorSpace<double, LO, GO, Node>(dofs_.ownedFree);
  // The load factor: one value, replicated on every rank.
  pSpace_ = Thyra::createVectorSpace<double, LO, GO, Node>(Tpetra::createLocalMapWithNode<LO, GO, Node>(1, comm_));
  nominal_ = createInArgs();
  auto x0 = Thyra::createMember(xSpace_);
  Thyra::assign(x0.ptr(), 0.0);
  nominal_.set_x(x0);
}

// This rank's particles (owned, ghosts, families) and the model with the problem's effects.
void PeridynamicEvaluator::buildModel() {
  const ProblemSpec& P = *problem_;
  LocalParticles lp;
  if (!P.distributed) {
    lp = localParticles(P.disc, owned_, &families_);
  } else {  // the share's indices are ascending in global id: the same order, renamed
    std::vector<long long> ownedIndex;
    for (long long g : owned_) ownedIndex.push_back(P.index(g));
    lp = localParticles(P.disc, ownedIndex, &families_);
    for (long long& g : lp.globalId) g = P.globalId[g];
    for (long long& g : families_.ghostMembers) g = P.globalId[g];
  }
  if (!P.modulusScale.empty())
    for (long long g : lp.globalId) lp.modulusScale.push_back(P.modulusScale[P.index(g)]);
  if (P.blocks.empty()) {
    model_ = std::make_unique<Model>(P.material, std::move(lp));
  } else {  // blocks: each local particle's index into the table of the blocks' materials
    const std::vector<int> index = P.blockIndex();
    for (long long g : lp.globalId) lp.material.push_back(index[P.index(g)]);
    model_ = std::make_unique<Model>(P.materials(), std::move(lp));
  }
  if (P.stressPoints) model_->enableStressPoints(P.stressPointSeed);
  else if (P.correspondence) model_->enableCorrespondence();
  if (P.control) model_->enableControl(P.controlSpec);
  if (P.blocks.empty()) {
    if (P.stabilization) model_->enableStabilization(P.stabilizationSpec());
    if (P.damage) model_->enableDamage(P.damageSpec);
  } else {
    std::vector<StabilizationSpec> stab;
    std::vector<DamageSpec> laws;
    for (const BlockSpec& blk : P.blocks) {
      stab.push_back(P.stabilizationSpec(blk));
      laws.push_back(blk.damage ? *blk.damage : P.damageSpec);
    }
    if (P.stabilization) model_->enableStabilization(stab);
    if (P.damage) model_->enableDamage(laws);
  }
}

// External force on owned free DOFs at load factor 1: f_ext = V b.
void PeridynamicEvaluator::buildExternalForce() {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  fextOwnedFree_ = Teuchos::rcp(new TVector(dofs_.ownedFree));
  {
    auto f = fextOwnedFree_->getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c)
        if (dofs_.overlapFreeLid[l * D + c] >= 0) {
          const int i = P.index(lp.globalId[l]);
          f[k++] = P.disc.volume[i] * P.bodyForce[static_cast<std::size_t>(i) * D + c];
        }
  }
  fextNorm_ = fextOwnedFree_->norm2();
}

// Machine epsilon times E times the norm, over free DOFs, of the force a unit strain produces.
void PeridynamicEvaluator::computeRoundoffScale() {
  const int D = problem_->dim();
  const auto scale = model_->unitStressForceScale();
  TVector ov(dofs_.overlapAll), owned(dofs_.ownedAll);
  auto od = ov.getDataNonConst();
  for (int l = 0; l < model_->particles().size(); ++l)
    for (int c = 0; c < D; ++c) od[l * D + c] = scale[l];
  od = Teuchos::null;
  owned.doExport(ov, *dofs_.allExport, Tpetra::ADD);
  auto wd = owned.getData();
  double s2 = 0, g2 = 0;
  for (int l = 0; l < model_->particles().numOwned; ++l)
    for (int c = 0; c < D; ++c)
      if (dofs_.overlapFreeLid[l * D + c] >= 0) s2 += wd[l * D + c] * wd[l * D + c];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, s2, Teuchos::outArg(g2));
  roundoffScale_ = std::numeric_limits<double>::epsilon() * problem_->stiffestModulus() * std::sqrt(g2);
}

// ---------------------------------------------------------------------------------------------
// Thyra
// ---------------------------------------------------------------------------------------------

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
  if (prescribesDisplacement_) {
    h = 1e-6 * std::max(1.0, std::abs(lambda));
    residualAt(lambda + h, fl);
    residualAt(lambda - h, *fm);
  } else {
    residualAt(1.0, fl);
    residualAt(0.0, *fm);
  }
  lambda_ = lambda;
  Thyra::Vp_StV(Teuchos::ptrFromRef(fl), -1.0, *fm);
  if (prescribesDisplacement_) Thyra::scale(0.5 / h, Teuchos::ptrFromRef(fl));
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
    op = Teuchos::rcp(new JacobianOperator(*assembler_, damage_->frozen(), dofs_.ownedFree));
  } else if (mode_ == JacobianMode::JacobianFree) {
    op = Teuchos::rcp(new DifferenceJacobianOperator(*this, dofs_.ownedFree, fdLambda_, problem_->disc.dx));
  } else {
    if (spareW_.is_null() || spareW_.strong_count() > 1) {
      spareW_ = Teuchos::rcp(new TCrsMatrix(assembler_->graphs(false).owned));
      spareW_->fillComplete();
    }
    op = spareW_;
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
  if (pm == PreconditionerMatrix::None && mode != JacobianMode::MatrixFree && !precFactory.is_null())
    throw std::invalid_argument(
        "PeridynamicEvaluator options: 'Preconditioner Matrix' = None hands the preconditioner the analytic "
        "matrix-free Jacobian: it needs 'Jacobian' = Matrix-Free");
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

Teuchos::RCP<const Teuchos::ParameterList> PeridynamicEvaluator::getValidParameters() {
  static const auto valid = [] {
    auto l = Teuchos::rcp(new Teuchos::ParameterList("Peridynamic Evaluator"));
    Teuchos::setStringToIntegralParameter<int>(
        "Jacobian", "Assembled", "how W = df/dx is given to the solver",
        Teuchos::tuple<std::string>("Assembled", "Matrix-Free", "Jacobian-Free"),
        Teuchos::tuple<std::string>("a Tpetra CrsMatrix", "the analytic product of the linearised kernels",
                                    "finite differences of f"),
        Teuchos::tuple<int>(0, 1, 2), l.get());
    Teuchos::setStringToIntegralParameter<int>(
        "Preconditioner Matrix", "Assembled", "matrix-free modes: what W_prec is built from",
        Teuchos::tuple<std::string>("Assembled", "Neighbours", "None"),
        Teuchos::tuple<std::string>("the assembled Jacobian", "its couplings within one horizon",
                                    "no matrix: the preconditioner is given the matrix-free Jacobian operator (Two-Stage)"),
        Teuchos::tuple<int>(0, 1, 2), l.get());
    l->set("Jacobian-Free Lambda", 1e-6, "Jacobian-free: the step h |v|_inf = lambda max(|x|_inf, dx) (> 0)");
    return l;
  }();
  return valid;
}

void PeridynamicEvaluator::setJacobian(const Teuchos::ParameterList& options,
                                       Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> precFactory) {
  Teuchos::ParameterList l(options);
  try {
    l.validateParametersAndSetDefaults(*getValidParameters());
  } catch (const std::exception& e) {
    // Teuchos' message spans several lines (source location, throw test, then "Error, ..."
    // naming the key and the value): keep the sentence from "Error" to the next blank line.
    const std::string what = e.what();
    auto at = what.find("Error");
    if (at == std::string::npos) at = 0;
    std::string sentence = what.substr(at, what.find("\n\n", at) - at);
    std::replace(sentence.begin(), sentence.end(), '\n', ' ');
    throw std::invalid_argument("PeridynamicEvaluator options: " + sentence);
  }
  const double fd = l.get<double>("Jacobian-Free Lambda");
  if (!(fd > 0) || !std::isfinite(fd))
    throw std::invalid_argument("PeridynamicEvaluator options: 'Jacobian-Free Lambda' must be positive and finite");
  const int mode = Teuchos::getIntegralValue<int>(l, "Jacobian");
  const int pm = Teuchos::getIntegralValue<int>(l, "Preconditioner Matrix");
  setJacobian(mode == 0 ? JacobianMode::Assembled : (mode == 1 ? JacobianMode::MatrixFree : JacobianMode::JacobianFree),
              pm == 0 ? PreconditionerMatrix::Assembled
                      : (pm == 1 ? PreconditionerMatrix::Neighbours : PreconditionerMatrix::None),
              precFactory, fd);
}

Teuchos::RCP<Tpetra::MultiVector<double, LO, GO>> PeridynamicEvaluator::rigidBodyModes() const {
  return dofs_.rigidBodyModes(*problem_, model_->particles());
}

Teuchos::RCP<TCrsMatrix> PeridynamicEvaluator::assembledJacobian(const Thyra::VectorBase<double>& x,
                                                                 bool neighbours) const {
  return assembledJacobianAt(localDisplacements(x), neighbours);
}

Teuchos::RCP<TCrsMatrix> PeridynamicEvaluator::assembledJacobianAt(const std::vector<double>& u, bool neighbours) const {
  auto A = Teuchos::rcp(new TCrsMatrix(assembler_->graphs(neighbours).owned));
  A->fillComplete();
  assembler_->internalForce(u, A.get(), neighbours, damage_->frozen());
  return A;
}

std::size_t PeridynamicEvaluator::matrixBytes() const { return assembler_->matrixBytes(); }

void PeridynamicEvaluator::commitHistory(const Thyra::VectorBase<double>& x) {
  if (!model_->hasHistory()) return;
  model_->commitState(localDisplacements(x));
}

std::vector<std::pair<long long, std::vector<double>>> PeridynamicEvaluator::ownedHistory() const {
  std::vector<std::pair<long long, std::vector<double>>> out;
  if (!model_->hasHistory()) return out;
  const int n = model_->stateDoublesPerParticle();
  const LocalParticles& p = model_->particles();
  out.reserve(p.numOwned);
  for (int i = 0; i < p.numOwned; ++i) {
    const double* s = model_->committedState(i);
    out.emplace_back(p.globalId[i], std::vector<double>(s, s + n));
  }
  return out;
}

void PeridynamicEvaluator::restoreHistory(const std::vector<std::pair<long long, std::vector<double>>>& states) {
  if (!model_->hasHistory()) return;
  const std::size_t n = static_cast<std::size_t>(model_->stateDoublesPerParticle());
  std::vector<double> all = model_->committedStates();
  for (const auto& [g, v] : states) {
    const int i = model_->particles().ownedLocal(g);
    if (i < 0) continue;
    if (v.size() != n)
      throw std::invalid_argument("the state of particle " + std::to_string(g) + " has " + std::to_string(v.size()) +
                                  " values; this model keeps " + std::to_string(n));
    std::copy(v.begin(), v.end(), all.begin() + static_cast<std::ptrdiff_t>(i * n));
  }
  model_->setCommittedStates(all);
}

std::vector<double> PeridynamicEvaluator::localDisplacements(const Thyra::VectorBase<double>& x) const {
  const ProblemSpec& P = *problem_;
  const int D = P.dim();
  const LocalParticles& lp = model_->particles();
  auto xt = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x));
  auto xd = xt->getData();
  std::optional<Eigen::Matrix3d> rotation;
  if (P.rotates()) rotation = rotationMatrix();
  TVector uOwned(dofs_.ownedAll);
  {
    auto ud = uOwned.getDataNonConst();
    LO k = 0;
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c) {
        const long long g = lp.globalId[l];
        if (dofs_.overlapFreeLid[l * D + c] >= 0) {
          const double v = xd[k++];
          if (!std::isfinite(v)) {
            std::ostringstream s;
            s << "displacement component " << c << " of particle " << g << " is not finite";
            throw EvaluationError(s.str(), g);
          }
          ud[l * D + c] = v;
        } else if (!rotation) {
          ud[l * D + c] = lambda_ * P.prescribed[static_cast<std::size_t>(P.index(g)) * D + c];
        } else {
          // Superposed rotation: every component of a prescribed particle is prescribed (the
          // scene checks), so the particle goes to R (X + lambda u_bar - c) + c.
          Vec3 ub = Vec3::Zero();
          const int i = P.index(g);
          for (int a = 0; a < D; ++a) ub[a] = P.prescribed[static_cast<std::size_t>(i) * D + a];
          const Vec3 X = P.disc.X[i];
          const Vec3 y = (*rotation) * (X + lambda_ * ub - P.rotation.center) + P.rotation.center;
          ud[l * D + c] = y[c] - X[c];
        }
      }
  }
  TVector uOv(dofs_.overlapAll);
  uOv.doImport(uOwned, *dofs_.allImport, Tpetra::INSERT);
  auto od = uOv.getData();
  return std::vector<double>(od.begin(), od.end());
}

Teuchos::RCP<TVector> PeridynamicEvaluator::internalForce(const Thyra::VectorBase<double>& x, TCrsMatrix* W,
                                                           bool neighbours) const {
  return assembler_->internalForce(localDisplacements(x), W, neighbours, damage_->frozen());
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
  if (!Wprec.is_null() && precMatrixKind_ == PreconditionerMatrix::None) {
    // No matrix: the preconditioner (Two-Stage) gets the matrix-free Jacobian at x. It shares
    // the model's kept linearisation with W_op, so the state is linearised once.
    if (precJ_.is_null()) precJ_ = Teuchos::rcp(new JacobianOperator(*assembler_, damage_->frozen(), dofs_.ownedFree));
    precJ_->setState(localDisplacements(*x));
    precA_ = Teuchos::null;
    auto op = Thyra::createConstLinearOp<double, LO, GO, Node>(
        Teuchos::rcp_implicit_cast<const Tpetra::Operator<double, LO, GO, Node>>(precJ_), xSpace_, xSpace_);
    // A preconditioner that needs a matrix now and then (the kept MUMPS factorisation) may ask
    // for the assembled Jacobian at this state during this set-up and the solve that follows
    // (its displacements are kept, so later evaluations at other states do not change it).
    precJ_->setAssembly([this, u = localDisplacements(*x)]() -> Teuchos::RCP<const TCrsMatrix> {
      return assembledJacobianAt(u, false);
    });
    precFactory_->initializePrec(Thyra::defaultLinearOpSource<double>(op), Wprec.get());
  } else if (!Wprec.is_null()) {
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
    residualFrom(*fint, *x, *f);
  }
}

void PeridynamicEvaluator::residualFrom(const TVector& fint, const Thyra::VectorBase<double>& x,
                                        Thyra::VectorBase<double>& f) const {
  auto ft = TOE::getTpetraVector(Teuchos::rcpFromRef(f));
  auto fd = ft->getDataNonConst();
  auto rd = fint.getData();
  auto fe = fextOwnedFree_->getData();
  const int D = problem_->dim();
  LO k = 0;
  const LocalParticles& lp = model_->particles();
  if (!problem_->rotates()) {
    for (int l = 0; l < lp.numOwned; ++l)
      for (int c = 0; c < D; ++c)
        if (dofs_.overlapFreeLid[l * D + c] >= 0) {
          fd[k] = rd[l * D + c] - lambda_ * fe[k];
          ++k;
        }
  } else {
    // Dead loads turn with the body: lambda R f_bar. A free particle has all its components
    // free (the scene checks), so its f_bar is fe[k .. k + D - 1].
    const Eigen::Matrix3d R = rotationMatrix();
    for (int l = 0; l < lp.numOwned; ++l) {
      if (dofs_.overlapFreeLid[l * D] < 0) continue;
      Vec3 fb = Vec3::Zero();
      for (int a = 0; a < D; ++a) fb[a] = fe[k + a];
      const Vec3 fr = R * fb;
      for (int c = 0; c < D; ++c, ++k) fd[k] = rd[l * D + c] - lambda_ * fr[c];
    }
  }
  const auto& frozen = damage_->frozen();
  if (!frozen.dofs.empty()) {
    auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
    for (const auto& [lid, value] : frozen.dofs) fd[lid] = frozen.stiffness * (xd[lid] - value);
  }
}

// ---------------------------------------------------------------------------------------------
// Damage and checkpoints (DamageBookkeeping does the work)
// ---------------------------------------------------------------------------------------------

PeridynamicEvaluator::BreakReport PeridynamicEvaluator::breakBonds(const Thyra::VectorBase<double>& x) {
  reactionX_ = Teuchos::null;
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  return damage_->breakBonds(localDisplacements(x), xd.getRawPtr());
}

PeridynamicEvaluator::BreakReport PeridynamicEvaluator::breakMostStretched(const Thyra::VectorBase<double>& x,
                                                                          double tol, double& maxStretch) {
  reactionX_ = Teuchos::null;
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  return damage_->breakMostStretched(localDisplacements(x), xd.getRawPtr(), tol, maxStretch);
}

std::vector<std::pair<long long, long long>> PeridynamicEvaluator::ownedBrokenBonds() const {
  return damage_->ownedBrokenBonds();
}

std::vector<std::pair<long long, double>> PeridynamicEvaluator::ownedFrozenDofs() const {
  return damage_->ownedFrozenDofs();
}

void PeridynamicEvaluator::restoreDamage(const std::vector<std::pair<long long, long long>>& broken,
                                         const std::vector<long long>& detached,
                                         const std::vector<std::pair<long long, double>>& frozen) {
  reactionX_ = Teuchos::null;
  damage_->restore(broken, detached, frozen);
}

std::vector<std::pair<long long, double>> PeridynamicEvaluator::ownedDofValues(const Thyra::VectorBase<double>& x) const {
  auto xd = TOE::getConstTpetraVector(Teuchos::rcpFromRef(x))->getData();
  std::vector<std::pair<long long, double>> out;
  out.reserve(xd.size());
  for (LO l = 0; l < static_cast<LO>(xd.size()); ++l) out.emplace_back(dofs_.ownedFreeDof[l], xd[l]);
  return out;
}

void PeridynamicEvaluator::setOwnedDofValues(Thyra::VectorBase<double>& x,
                                             const std::vector<std::pair<long long, double>>& values) const {
  auto xd = TOE::getTpetraVector(Teuchos::rcpFromRef(x))->getDataNonConst();
  const int D = problem_->dim();
  const LocalParticles& lp = model_->particles();
  for (const auto& [dof, value] : values) {
    const int lid = dofs_.ownedFreeLidOf(lp, dof, D);
    if (lid >= 0) xd[lid] = value;
  }
}

long long PeridynamicEvaluator::freeDof(long long p, int c) const {
  const LocalParticles& lp = model_->particles();
  int l = lp.ownedLocal(p);
  if (l < 0) {
    const auto end = lp.globalId.end(), it = std::lower_bound(lp.globalId.begin() + lp.numOwned, end, p);
    if (it == end || *it != p)
      throw std::out_of_range("perinox: freeDof: particle " + std::to_string(p) + " is neither owned by rank " +
                              std::to_string(comm_->getRank()) + " nor one of its ghosts");
    l = static_cast<int>(it - lp.globalId.begin());
  }
  return dofs_.overlapFreeGid[static_cast<std::size_t>(l) * problem_->dim() + c];
}

// ---------------------------------------------------------------------------------------------
// Diagnostics
// ---------------------------------------------------------------------------------------------

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
      if (dofs_.overlapFreeLid[l * D + c] < 0) s += rd[l * D + c] * rd[l * D + c];
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
    if (const int l = ownedIndex(p); l >= 0)
      for (int c = 0; c < D; ++c)
        if (problem_->isFixed(p, c)) s[c] += rd[l * D + c];
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, D, s.data(), g.data());
  return g;
}

std::vector<double> PeridynamicEvaluator::meanDisplacement(const Thyra::VectorBase<double>& x,
                                                           const std::vector<int>& particles) const {
  const int D = problem_->dim();
  const auto u = ownedDisplacements(x);
  std::vector<double> s(D + 1, 0.0), g(D + 1, 0.0);
  for (int p : particles)
    if (const int l = ownedIndex(p); l >= 0) {
      for (int c = 0; c < D; ++c) s[c] += u[static_cast<std::size_t>(l) * D + c];
      s[D] += 1;
    }
  Teuchos::reduceAll(*comm_, Teuchos::REDUCE_SUM, D + 1, s.data(), g.data());
  std::vector<double> mean(D);
  for (int c = 0; c < D; ++c) mean[c] = g[D] > 0 ? g[c] / g[D] : 0.0;
  return mean;
}

std::vector<double> PeridynamicEvaluator::ownedDisplacements(const Thyra::VectorBase<double>& x) const {
  auto u = localDisplacements(x);
  u.resize(static_cast<std::size_t>(model_->particles().numOwned) * problem_->dim());
  return u;
}

std::vector<ParticleOutput> PeridynamicEvaluator::ownedOutputs(const Thyra::VectorBase<double>& x) const {
  return model_->outputs(localDisplacements(x));
}

int PeridynamicEvaluator::negativePivots(const Thyra::VectorBase<double>& x) const {
  return negativePivotCount(*assembledJacobian(x, false), dofs_, *comm_);
}

}  // namespace perinox
