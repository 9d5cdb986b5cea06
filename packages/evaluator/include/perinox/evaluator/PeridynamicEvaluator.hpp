#pragma once
// Thyra::ModelEvaluator for quasi-static peridynamics over Tpetra:
//   x = free displacement DOFs of the particles this rank owns,
//   f(x) = f_int(u(x, lambda)) - lambda f_ext,   W = df/dx assembled (symmetric where the physics is).
// Prescribed DOFs (fictitious layers, pins, rollers) are not unknowns; their values are
// lambda * prescribed. This class is the Thyra adapter: the DOF maps, graphs and assembly are in
// Assembly.hpp (DofMaps, Assembler), the matrix-free operators in JacobianOperators.hpp, the
// damage state in DamageBookkeeping.hpp.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_LinearOpWithSolveFactoryBase.hpp>
#include <Thyra_PreconditionerFactoryBase.hpp>
#include <Thyra_StateFuncModelEvaluatorBase.hpp>
#include <Teuchos_ParameterList.hpp>
#include <memory>

#include "perinox/evaluator/Assembly.hpp"
#include "perinox/evaluator/DamageBookkeeping.hpp"
#include "perinox/evaluator/Problem.hpp"

namespace perinox {

/// How the Newton solver gets W = df/dx: an assembled sparse matrix; the analytic matrix-free
/// product (linearised kernels, nothing assembled); or finite differences of f (Jacobian-free,
/// built by the Newton solver around this evaluator).
enum class JacobianMode { Assembled, MatrixFree, JacobianFree };
/// The matrix a matrix-free solve's preconditioner is built from: the assembled Jacobian, its
/// part that couples particles within one horizon (memory proportional to the family size), or
/// none: the preconditioner is handed the matrix-free Jacobian operator itself (the Two-Stage
/// preconditioner, which needs only J v products and its auxiliary matrix).
enum class PreconditionerMatrix { Assembled, Neighbours, None };

class JacobianOperator;

class PeridynamicEvaluator : public Thyra::StateFuncModelEvaluatorBase<double> {
 public:
  PeridynamicEvaluator(Teuchos::RCP<const Teuchos::Comm<int>> comm,
                       std::shared_ptr<const ProblemSpec> problem);

  // --- loading ---
  /// The load factor lambda is the model's parameter p(0) (one value, "Load Factor"; DfDp(0) =
  /// df/dlambda is supported). An evaluation given p(0) evaluates at that load factor and makes it
  /// the current one; without p(0) the current one is used (set here, or by the last evaluation
  /// with p). The diagnostics (external-force and reaction norms, displacements, damage) use the
  /// current one.
  void setLoadFactor(double lambda) { lambda_ = lambda; }
  double loadFactor() const { return lambda_; }
  /// df/dlambda at x and the current load factor, on the owned free DOFs (what DfDp(0) returns).
  /// Dead loads only (every prescribed value zero): exactly f(x, 1) - f(x, 0) = -R f_ext. With
  /// prescribed displacements: the central difference (f(x, lambda + h) - f(x, lambda - h)) / 2h,
  /// h = 1e-6 max(1, |lambda|) (f is smooth in lambda: truncation O(h^2), rounding eps |f_int| / h).
  void loadDerivative(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& dfdl) const;

  // --- Thyra ---
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_x_space() const override { return xSpace_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_f_space() const override { return xSpace_; }
  Thyra::ModelEvaluatorBase::InArgs<double> getNominalValues() const override;
  Teuchos::RCP<Thyra::LinearOpBase<double>> create_W_op() const override;
  Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> get_W_factory() const override {
    return wFactory_;
  }
  void set_W_factory(Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> f) { wFactory_ = f; }
  /// Selects how W is provided. With a preconditioner factory, W_prec is supported: the model
  /// builds it from the assembled Jacobian or its direct-neighbour part (pm). A MueLu factory is
  /// given the rigid-body modes as near-null space. Call before the first evaluation.
  void setJacobian(JacobianMode mode, PreconditionerMatrix pm,
                   Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> precFactory, double fdLambda = 1e-6);
  /// The evaluator's own options, as a list: "Jacobian" (Assembled, Matrix-Free, Jacobian-Free),
  /// "Preconditioner Matrix" (Assembled, Neighbours, None), "Jacobian-Free Lambda" (> 0). Everything
  /// else (the linear solver, the preconditioner) is injected as a Stratimikos factory.
  static Teuchos::RCP<const Teuchos::ParameterList> getValidParameters();
  /// setJacobian from such a list (validated: std::invalid_argument, one sentence naming the key).
  void setJacobian(const Teuchos::ParameterList& options, Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> precFactory);
  JacobianMode jacobianMode() const { return mode_; }
  /// The preconditioner factory a matrix-free mode builds W_prec with (null otherwise).
  Teuchos::RCP<const Thyra::PreconditionerFactoryBase<double>> preconditionerFactory() const { return precFactory_; }
  Teuchos::RCP<Thyra::PreconditionerBase<double>> create_W_prec() const override;
  /// W at x assembled, whatever the Jacobian mode (for diagnostics, the explicit solver, and
  /// preconditioners); neighbours keeps only couplings within one horizon.
  Teuchos::RCP<TCrsMatrix> assembledJacobian(const Thyra::VectorBase<double>& x, bool neighbours = false) const;
  /// Bytes held by the sparse matrices built so far (owned and overlapping; values, indices, rows).
  std::size_t matrixBytes() const;
  /// Rigid-body modes on the owned free DOFs (1 in 1D, 3 in 2D, 6 in 3D).
  Teuchos::RCP<Tpetra::MultiVector<double, LO, GO>> rigidBodyModes() const;
  Thyra::ModelEvaluatorBase::InArgs<double> createInArgs() const override;
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_p_space(int l) const override;
  Teuchos::RCP<const Teuchos::Array<std::string>> get_p_names(int l) const override;

  // --- diagnostics and output ---
  /// |lambda f_ext|_2 over free DOFs (global).
  double externalForceNorm() const;
  /// The superposed rigid rotation at the current load factor (identity without one).
  Eigen::Matrix3d rotationMatrix() const;
  /// Round-off scale of the residual: machine epsilon times the norm, over free DOFs, of the
  /// internal force a unit strain would produce (E times Model::unitStressForceScale). Rounding in
  /// F (formed as I + H) is amplified by E, so |R| cannot be resolved much below this.
  double roundoffScale() const { return roundoffScale_; }
  /// |reaction|_2: the internal force summed on prescribed DOFs at x (global).
  double reactionNorm(const Thyra::VectorBase<double>& x) const;
  /// Displacements of all owned particles (owned * dim, interleaved) for the state x.
  std::vector<double> ownedDisplacements(const Thyra::VectorBase<double>& x) const;
  /// Per-owned-particle F and Cauchy stress at x.
  std::vector<ParticleOutput> ownedOutputs(const Thyra::VectorBase<double>& x) const;
  /// The reaction force (sum of internal forces over prescribed DOFs of the given particles),
  /// global, per component.
  std::vector<double> reactionOn(const Thyra::VectorBase<double>& x, const std::vector<int>& particles) const;
  /// The mean displacement of the given particles (global ids, any rank), per component (global).
  std::vector<double> meanDisplacement(const Thyra::VectorBase<double>& x, const std::vector<int>& particles) const;

  // --- stability ---
  /// Number of negative pivots of the tangent at x (its inertia, by Sylvester's law), from a
  /// sparse LDL^T of W gathered on rank 0 (Eigen). A diagnostic for symmetric tangents: memory
  /// and time are those of a serial factorisation. Returns -1 if W is not symmetric to 1e-8.
  int negativePivots(const Thyra::VectorBase<double>& x) const;

  // --- damage (seed 000 Fig. 8) ---
  using BreakReport = perinox::BreakReport;
  /// After a converged step: breaks every bond with s >= s_cr at x, then detaches (isolates
  /// and freezes) every particle left with a singular shape tensor, repeating until none is,
  /// and every particle of a free-floating fragment (cut off from all prescribed DOFs).
  BreakReport breakBonds(const Thyra::VectorBase<double>& x);
  /// For a load step that cannot be converged (a snap-back of softening bonds under displacement
  /// control): breaks, at the converged state x, the intact bonds whose stretch is within
  /// tol of the largest one, if that one is in the softening band (s >= s_min; none otherwise),
  /// then detaches as breakBonds does. maxStretch receives the largest stretch.
  BreakReport breakMostStretched(const Thyra::VectorBase<double>& x, double tol, double& maxStretch);
  // --- history (materials with internal variables, e.g. plasticity) ---
  /// Whether some material has history. Evaluations never change it; commitHistory does.
  bool hasHistory() const { return model_->hasHistory(); }
  /// Makes the trial state at x (at the current load factor) the committed one: the
  /// HistoryCommit of LoadStepper and ArcLengthStepper, and what a host that drives Newton
  /// itself calls once per accepted step, before reading outputs. Collective (x's ghosts are
  /// imported); does nothing without history.
  void commitHistory(const Thyra::VectorBase<double>& x);
  /// The committed states of the owned particles as (global id, its block of
  /// Model::stateDoublesPerParticle doubles), for checkpoints.
  std::vector<std::pair<long long, std::vector<double>>> ownedHistory() const;
  /// Restores committed states (pairs of other ranks' particles are ignored; an owned particle
  /// absent from the list keeps its state). Throws std::invalid_argument for a block of the wrong size.
  void restoreHistory(const std::vector<std::pair<long long, std::vector<double>>>& states);
  // --- checkpoints (restart of long runs) ---
  /// Bonds of the owned particles broken so far, as (owned particle, neighbour) global ids.
  std::vector<std::pair<long long, long long>> ownedBrokenBonds() const;
  // DOFs are named particle * dim + component (global particle id): a name that does not depend
  // on the rank count or the partition, unlike the free-DOF numbering of the solution map.
  /// The owned free DOFs of x as (particle * dim + component, value).
  std::vector<std::pair<long long, double>> ownedDofValues(const Thyra::VectorBase<double>& x) const;
  /// Sets the owned free DOFs of x from (particle * dim + component, value) pairs; pairs of other
  /// ranks' or of prescribed DOFs are ignored.
  void setOwnedDofValues(Thyra::VectorBase<double>& x, const std::vector<std::pair<long long, double>>& values) const;
  /// Frozen DOFs of the owned detached particles: (particle * dim + component, frozen value).
  std::vector<std::pair<long long, double>> ownedFrozenDofs() const;
  /// Restores the damage of a checkpoint on a fresh evaluator (every rank, the same arguments):
  /// removes the bonds (global id pairs, either order), detaches the particles and freezes their
  /// owned DOFs at the given values (particle * dim + component -> value).
  void restoreDamage(const std::vector<std::pair<long long, long long>>& broken, const std::vector<long long>& detached,
                     const std::vector<std::pair<long long, double>>& frozen);
  /// Damage index of the owned particles.
  std::vector<double> ownedDamage() const { return model_->damageIndex(); }
  const std::vector<long long>& detachedParticles() const { return damage_->detached(); }

  const ProblemSpec& problem() const { return *problem_; }
  const Model& model() const { return *model_; }
  /// The rank's families as built (owned in local ids, ghosts' in global ids; Partition.hpp).
  const LocalFamilies& localFamilies() const { return families_; }
  /// The particles this rank owns (global ids, sorted; `Discretization/Partition` chose them).
  /// The owned arrays of this class (displacements, outputs, damage) are in this order.
  const std::vector<long long>& ownedParticles() const { return owned_; }
  /// Whether a non-zero displacement is prescribed anywhere (over all ranks' shares).
  bool prescribesDisplacement() const { return prescribesDisplacement_; }
  /// Owned + ghost particles this rank evaluates (the ghosts: family members owned elsewhere).
  long long localParticleCount() const { return model_->particles().size(); }
  /// Position of global particle g in ownedParticles(), or -1 if another rank owns it.
  int ownedIndex(long long g) const { return model_->particles().ownedLocal(g); }
  long long numFreeDofs() const { return dofs_.numFree; }
  Teuchos::RCP<const TMap> ownedFreeMap() const { return dofs_.ownedFree; }
  Teuchos::RCP<const Teuchos::Comm<int>> comm() const { return comm_; }
  /// Global free DOF id (the solution map's numbering) of component c of particle p, which must
  /// be local to this rank (owned, or a ghost), or -1 if prescribed. Throws std::out_of_range for
  /// a particle this rank does not hold (no rank holds a numbering of the whole body).
  long long freeDof(long long p, int c) const;

 private:
  Thyra::ModelEvaluatorBase::OutArgs<double> createOutArgsImpl() const override;
  void evalModelImpl(const Thyra::ModelEvaluatorBase::InArgs<double>& in,
                     const Thyra::ModelEvaluatorBase::OutArgs<double>& out) const override;
  /// f from the owned internal force: f_int - lambda f_ext on the free DOFs, frozen rows.
  void residualFrom(const TVector& fint, const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& f) const;
  /// Local displacements (local particles * dim) for the state x at the current load factor.
  std::vector<double> localDisplacements(const Thyra::VectorBase<double>& x) const;
  /// The Jacobian assembled at local displacements (owned and ghost particles, as localDisplacements).
  Teuchos::RCP<TCrsMatrix> assembledJacobianAt(const std::vector<double>& u, bool neighbours) const;
  /// Owned-all internal force vector (owned particles * dim) at x (with W: the Jacobian too).
  Teuchos::RCP<TVector> internalForce(const Thyra::VectorBase<double>& x, TCrsMatrix* W,
                                      bool neighbours = false) const;
  void buildModel();
  void buildExternalForce();
  void computeRoundoffScale();
  double reactionNormOf(const TVector& fint) const;

  Teuchos::RCP<const Teuchos::Comm<int>> comm_;
  std::shared_ptr<const ProblemSpec> problem_;
  std::unique_ptr<Model> model_;
  std::vector<long long> owned_;  // owned particles' global ids, sorted
  LocalFamilies families_;        // the local families as built (graph, broken bonds)
  mutable double lambda_ = 0.0;  // the current load factor (an evaluation with p(0) sets it)
  DofMaps dofs_;
  std::unique_ptr<Assembler> assembler_;
  std::unique_ptr<DamageBookkeeping> damage_;

  double fdLambda_ = 1e-6;
  JacobianMode mode_ = JacobianMode::Assembled;
  PreconditionerMatrix precMatrixKind_ = PreconditionerMatrix::Assembled;
  Teuchos::RCP<Thyra::PreconditionerFactoryBase<double>> precFactory_;
  mutable Teuchos::RCP<TCrsMatrix> precA_;
  // Preconditioner Matrix = None: the matrix-free Jacobian the preconditioner is given.
  mutable Teuchos::RCP<JacobianOperator> precJ_;
  // The last assembled W_op handed out: create_W_op gives it again once nobody else holds it (a
  // Newton solve after the tangent predictor's, the next load step's), instead of allocating
  // and zeroing a new matrix of the same graph (every evaluation overwrites its values).
  mutable Teuchos::RCP<TCrsMatrix> spareW_;
  // The reaction norm of the last residual evaluation, with its state and load factor, kept
  // when no external force acts (only then do the convergence tests normalise by it): asked for
  // at the state NOX just evaluated, it then costs no second residual. Cleared when bonds break.
  mutable Teuchos::RCP<Thyra::VectorBase<double>> reactionX_;
  mutable double reactionNorm_ = 0.0, reactionLambda_ = 0.0;

  Teuchos::RCP<TVector> fextOwnedFree_;  // f_ext at lambda = 1 on owned free DOFs
  double fextNorm_ = 0.0;                 // its global 2-norm (the load never changes)
  double roundoffScale_ = 0.0;
  bool prescribesDisplacement_ = false;  // over all ranks (P.prescribesDisplacement() is the share's)

  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> xSpace_, pSpace_;
  Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> wFactory_;
  Thyra::ModelEvaluatorBase::InArgs<double> nominal_;
};

}  // namespace perinox
