#pragma once
// The peridynamic model on one rank: particles it owns plus the ghosts their families reach,
// and the effects a scene enables. Each owned particle i is an "element": the particles
// {i} u H_i, its bond force states T_i<xi_ij>, and the element residual and tangent they give:
//
//     r_i  -= V_i V_j T_i<xi_ij>,   r_j += V_i V_j T_i<xi_ij>      (force units; R = f_int - f_ext)
//
// This is the gradient of the particle's stored energy V_i W(F_i) (plus the stabilisation
// energy), so the element tangent is symmetric for every energy-derived effect.
// No Trilinos here: the evaluator maps local particles to degrees of freedom.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "perinox/core/EvaluationError.hpp"  // what the model throws at a state it cannot evaluate
#include "perinox/material/Material.hpp"

namespace perinox {

/// What one rank sees of the discretisation. Local ids: [0, numOwned) are owned particles,
/// [numOwned, size) ghosts (family members of owned particles owned elsewhere).
struct LocalParticles {
  int dim = 2;
  int numOwned = 0;
  std::vector<long long> globalId;
  std::vector<Eigen::Vector3d> X;
  std::vector<double> volume;
  // Families of owned particles only, with local neighbour ids (CSR). Broken bonds are removed.
  std::vector<std::int64_t> famOffset;
  std::vector<int> famIndex;
  std::vector<double> modulusScale;  // per local particle (E_i / E); empty for a uniform material
  // Per local particle (owned and ghosts): its index into the model's material table (a block's
  // material, stabilisation and damage law); empty when every particle has material 0.
  std::vector<int> material;
  int size() const { return static_cast<int>(X.size()); }
  /// Local id of global particle g if this rank owns it (owned ids are sorted), else -1.
  int ownedLocal(long long g) const {
    const auto end = globalId.begin() + numOwned;
    const auto it = std::lower_bound(globalId.begin(), end, g);
    return it != end && *it == g ? static_cast<int>(it - globalId.begin()) : -1;
  }
};

/// Per-particle workspace handed from the model to each effect.
template <int D>
struct BondWork {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  int i = -1;        // local id of the particle
  int m = 0;         // family size
  const int* nbr = nullptr;
  double Vi = 0;
  std::vector<Vec> xi, Y, h;   // reference bond, deformed bond, h_j = K^-1 xi_j
  std::vector<double> Vj;
  Mat K, Kinv, F;
  // Outputs accumulated by the effects:
  std::vector<Vec> t;          // T_i<xi_ij>, j = 0..m-1
  std::vector<Mat> tan;        // dT_ij/du_k, index j*(m+1) + k; k = 0 is particle i, k = 1+l member l
  // With diagonalOnly, tan holds only dT(j, 0) and dT(j, j + 1) (index 2j and 2j + 1): all the
  // element's diagonal blocks need (Model::addJacobianDiagonal).
  bool diagonalOnly = false;
  Mat& dT(int j, int k) { return diagonalOnly ? tan[2 * j + (k == 0 ? 0 : 1)] : tan[j * (m + 1) + k]; }
  /// Calls f(k) for every k an effect's loop over dT(j, k) must fill: 0..m, or only 0 and j + 1.
  template <class F>
  void forColumns(int j, F&& f) const {
    if (diagonalOnly) {
      f(0);
      f(j + 1);
    } else {
      for (int k = 0; k <= m; ++k) f(k);
    }
  }
  /// dF/du_k = e_c (x) g_k: g_0 = -sum_l V_l h_l, g_{1+l} = V_l h_l.
  Vec g(int k) const;
  Vec gsum;                    // sum_l V_l h_l (so g_0 = -gsum)
  // Directional derivative along a displacement direction v (matrix-free products):
  std::vector<Vec> dY;         // dY_l = v_j - v_i
  Mat dF;                      // dF = sum_l V_l dY_l (x) h_l
  std::vector<Vec> dt;         // dT_i<xi_ij>[v], accumulated by the effects
  // Matrix-free products repeat at one state (one per Krylov iteration): an effect may keep
  // per-particle data of its linearisation in cache (cacheSize() doubles, or nullptr), filling
  // it when cacheFresh and reading it otherwise.
  double* cache = nullptr;
  bool cacheFresh = false;
  // Materials with history: the committed state of particle i's points (stateStride doubles a
  // point; point p of the stress-point effect at state + p * stateStride), or nullptr when no
  // material has history. trial, when not null, is where an evaluation writes the trial state
  // (only Model::commitState sets it, to state itself).
  const double* state = nullptr;
  double* trial = nullptr;
  int stateStride = 0;
  /// Point p's committed state and where its trial state goes (nullptr when there is none).
  const double* pointState(int p) const { return state ? state + p * stateStride : nullptr; }
  double* pointTrial(int p) const { return trial ? trial + p * stateStride : nullptr; }
  // Sums over the family a repeated product's affine form may use (filled only for it):
  double Vsum = 0;             // sum_l V_l
  Vec VdYsum;                  // sum_l V_l dY_l
  Vec VUsum;                   // sum_l V_l (u_j - u_i) at the kept state (with damage only)
};

/// A repeated matrix-free product's bond force states when they are affine in the bond: the
/// same A, c and k give dt_l = A xi_l + c dY_l + k for every bond l of the particle.
template <int D>
struct AffineDirectional {
  Eigen::Matrix<double, D, D> A = Eigen::Matrix<double, D, D>::Zero();
  double c = 0;
  Eigen::Matrix<double, D, 1> k = Eigen::Matrix<double, D, 1>::Zero();
};

/// One effect: adds its bond force states (and their derivatives) for particle i.
template <int D>
class ForceEffect {
 public:
  virtual ~ForceEffect() = default;
  virtual const char* name() const = 0;
  /// Called whenever the local families change (set-up, bonds broken).
  virtual void prepare(const LocalParticles&) {}
  /// Adds to w.t (and to w.tan if tangent). Throws EvaluationError on an invalid state.
  virtual void addForces(BondWork<D>& w, bool tangent) const = 0;
  /// Adds the force states to w.t and their directional derivative along w.dY (with w.dF) to
  /// w.dt, without forming dT/du: the kernel of the matrix-free Jacobian-vector product.
  virtual void addDirectional(BondWork<D>& w) const = 0;
  /// Doubles per particle this effect keeps between matrix-free products at one state (0: none).
  virtual int cacheSize() const { return 0; }
  /// Whether this effect's force states and their directional derivatives at a kept state (a
  /// repeated product) are affine in the bond (addAffineDirectional). When every effect of a
  /// model says so, such a product visits each bond twice with a few flops and nothing else.
  virtual bool affineDirectional() const { return false; }
  /// Adds this effect's share of the affine form dt_l = A xi_l + c dY_l + k, from its cache
  /// (filled by the last addDirectional at this state) and w.i, w.Vi, w.Kinv, w.dF, w.Vsum and
  /// w.VdYsum alone: nothing per bond is filled. With damage, t is not null: add also the force
  /// states' own form at the kept state, t_l = A xi_l + c Y_l + k, from w.F and w.VUsum (the
  /// model softens bond by bond, which needs the unsoftened t of the bonds in the band).
  virtual void addAffineDirectional(const BondWork<D>& /*w*/, AffineDirectional<D>& /*dt*/,
                                    AffineDirectional<D>* /*t*/) const {}
};

/// Receives element contributions. particles: local ids of the element (i first);
/// r: n*D values; K: (n*D)x(n*D) dense row-major, or nullptr when no tangent was asked.
class ElementSink {
 public:
  virtual ~ElementSink() = default;
  virtual void add(const int* particles, int n, const double* r, const double* K) = 0;
};

/// Stabilisation parameters (Silling 2017; seed 000 eqs 35-44).
struct StabilizationSpec {
  /// C's default: "compute it" (ProblemSpec::stabilizationSpec gives micromodulusC); the model
  /// itself needs a value >= 0.
  static constexpr double kFromMaterial = -1.0;
  double G = 0.0;             // dimensionless
  double C = kFromMaterial;   // micromodulus / horizon (see micromodulusC)
  /// How G enters. Silling: T_z = (G C / w0_i) z. PeridigmHourglass: G is Peridigm's
  /// `Hourglass Coefficient`, and particle i takes Silling's G_i = G delta S_i / (3 V_i), S_i =
  /// sum_j V_j / |xi_ij| over its intact bonds: the trace of the family's stabilising stiffness
  /// then equals that of Peridigm's hourglass force (docs/peridigm.md derives it).
  enum class Form { Silling, PeridigmHourglass } form = Form::Silling;
  double horizon = 0.0;       // delta (PeridigmHourglass; ProblemSpec::stabilizationSpec sets it)
};

/// Supplementary-force controls of zero-energy modes (Breitenfeld et al. 2014; seed 001 eqs 7-8):
/// springs T_a = C w (u_j - u_i); average displacement state T_a = C sum_l w (u_l - u_i) V_l.
struct ControlSpec {
  enum class Kind { Springs, AverageDisplacement } kind = Kind::Springs;
  double C = 0.0;
};

/// Bond softening of the implicit damage model (seed 000, eqs 45-54):
/// T_s(s) = 1 below sMin, 1/2 (1 - tanh(beta (sMin + sCr - 2 s) / (sMin - sCr))) in the band,
/// 0 from sCr on. Bonds with s >= sCr are broken for good after a converged load step.
/// The paper's law jumps at both ends of the band (T_s(sMin+) = 1/2 (1 + tanh beta) = 0.9975 and
/// T_s(sCr-) = 1/2 (1 - tanh beta) = 0.0025 for beta = 3). Softening::Continuous rescales the tanh
/// so that it is exactly 1 at sMin and 0 at sCr: T_s = 1/2 (1 - tanh(n) / tanh(beta)), continuous
/// (only its slope still jumps at the two ends).
struct DamageSpec {
  double sMin = 0.0015;
  double sCr = 0.002;
  double beta = 3.0;
  enum class Softening { Paper, Continuous } softening = Softening::Paper;
  /// Ductile failure: > 0, a bond also breaks (after a converged step) when the mean of the
  /// equivalent plastic strains of its two ends, at the step's trial state, reaches this.
  double criticalPlasticStrain = 0.0;
  /// false: the stretch neither softens nor breaks bonds (only criticalPlasticStrain does).
  bool stretchCriterion = true;
};

/// T_s(s) and dT_s/ds (dT_s/ds uses the corrected derivative of FORMULATION.md).
inline void bondSoftening(const DamageSpec& d, double s, double& Ts, double& dTs) {
  if (s < d.sMin || !d.stretchCriterion) {
    Ts = 1.0;
    dTs = 0.0;
  } else if (s < d.sCr) {
    const double n = d.beta * (d.sMin + d.sCr - 2.0 * s) / (d.sMin - d.sCr);
    const double th = std::tanh(n);
    const double dn = -2.0 * d.beta / (d.sMin - d.sCr);  // dn/ds
    if (d.softening == DamageSpec::Softening::Continuous) {
      const double tb = std::tanh(d.beta);
      Ts = 0.5 * (1.0 - th / tb);
      dTs = -0.5 * (1.0 - th * th) * dn / tb;
    } else {
      Ts = 0.5 * (1.0 - th);
      dTs = -0.5 * (1.0 - th * th) * dn;
    }
  } else {
    Ts = 0.0;
    dTs = 0.0;
  }
}

/// C of the stabilisation term for a material and horizon (FORMULATION.md):
/// 1D 2E/(A delta^3), 2D 12 k'/(pi h delta^4), 3D 18 k/(pi delta^5).
double micromodulusC(const MaterialSpec& m, double delta, double thickness);

/// Per-particle output of the model.
struct ParticleOutput {
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d cauchy = Eigen::Matrix3d::Zero();
  double eqps = 0.0;     // equivalent plastic strain of the committed state (0 for elastic materials)
  bool yielded = false;  // the last committed step flowed plastically at this particle
  bool valid = true;  // false if F was inverted (stress then written as zero)
};

/// The composed model. Effects are added once; effects a scene leaves off are never built.
class Model {
 public:
  Model(const MaterialSpec& material, LocalParticles particles);
  /// Several materials (blocks): particle l has materials[particles.material[l]] (all of them the
  /// first when particles.material is empty). Each particle's element uses its own material: its
  /// P and A, and, with enableStabilization / enableDamage given per-material tables, its G and C
  /// and damage law (a bond between two materials takes the law of the smaller critical stretch).
  Model(const std::vector<MaterialSpec>& materials, LocalParticles particles);
  ~Model();
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;

  void enableCorrespondence();
  void enableStabilization(const StabilizationSpec& s);
  /// Per material (one entry per material of the table): particle i's T_z uses its material's G and C.
  void enableStabilization(const std::vector<StabilizationSpec>& perMaterial);
  /// Supplementary-force control (springs or average displacement state).
  void enableControl(const ControlSpec& c);
  /// Stress points (seed 001): the correspondence force state computed per stress point from
  /// the bonds it owns (nearest-neighbour families; arrangements drawn from the seed and the
  /// global particle id). Replaces the plain correspondence effect.
  void enableStressPoints(unsigned seed = 2018);
  /// Softens every bond force (of all effects) by T_s(s); see DamageSpec.
  void enableDamage(const DamageSpec& d);
  /// Per material: a bond within one material softens and breaks by that material's law; a bond
  /// between two takes the law with the smaller critical stretch (equal ones: the lower index), so
  /// both ends (and ranks) choose the same.
  void enableDamage(const std::vector<DamageSpec>& perMaterial);
  /// The damage law of the bond between local particles i and j (damage enabled).
  const DamageSpec& bondDamage(int i, int j) const;
  bool damageEnabled() const { return damage_.has_value(); }
  std::vector<std::string> effectNames() const;

  /// Breaks, for good, every bond of an owned particle whose stretch at u is >= sCr. Both
  /// ends of a bond compute the same stretch bit for bit, so ranks agree without talking.
  /// Returns the number of bonds broken, each counted on the rank owning its lower-id end
  /// (so a sum over ranks counts every bond once).
  long long breakBonds(const std::vector<double>& u);
  /// The same, with the ductile criterion (DamageSpec::criticalPlasticStrain) on the equivalent
  /// plastic strains of the local particles (owned and ghosts, as trialPlasticStrain gives them
  /// on every rank; both ends of a bond must see the same two values).
  long long breakBonds(const std::vector<double>& u, const std::vector<double>& plasticStrain);
  /// Per owned particle, the equivalent plastic strain of the trial state at u (the largest of its
  /// stress points'); zeros without history. Nothing is committed.
  std::vector<double> trialPlasticStrain(const std::vector<double>& u) const;
  /// Whether some damage law breaks bonds by plastic strain.
  bool ductileCriterion() const;
  /// The same with another threshold: breaks every intact bond with stretch >= sBreak.
  long long breakBondsAbove(const std::vector<double>& u, double sBreak);
  /// The largest stretch of an intact bond of an owned, attached particle at u (-inf if none).
  double maxIntactStretch(const std::vector<double>& u) const;
  /// Removes every bond to or from the given particles (global ids) and empties their families.
  void isolate(const std::vector<long long>& globalIds);
  /// Owned particles (global ids) whose shape tensor is singular, not yet detached.
  std::vector<long long> singularParticles() const;
  /// Marks owned particles as detached (their element is skipped). Call isolate() first.
  void markDetached(const std::vector<long long>& globalIds);
  bool detached(int ownedLocal) const { return !detached_.empty() && detached_[ownedLocal]; }
  /// Per local particle, sum over the owned bonds touching it of V_i V_j |K_i^-1 xi_ij|: the
  /// force a unit stress would put on it. Times E and machine epsilon it bounds the round-off of
  /// the residual (used for the convergence floor).
  std::vector<double> unitStressForceScale() const;
  /// Damage index phi_i = 1 - sum_intact V_j / sum_initial V_j of the owned particles.
  std::vector<double> damageIndex() const;

  const LocalParticles& particles() const { return particles_; }
  const Material& material() const { return materials_.front(); }
  /// The material of local particle l.
  const Material& material(int l) const {
    return particles_.material.empty() ? materials_.front() : materials_[particles_.material[l]];
  }
  const std::vector<Material>& materials() const { return materials_; }

  /// Evaluates every owned element at local displacements u (size*dim, interleaved) and hands
  /// each to the sink (tangent only if wantTangent).
  void evaluate(const std::vector<double>& u, ElementSink& sink, bool wantTangent) const;

  /// Matrix-free tangent product: adds (df_int/du) v, summed over the owned elements, to jv
  /// (local particles * dim, interleaved, like u and v). The element tangents are never formed:
  /// each effect linearises its force states along v. Detached particles are skipped.
  void applyTangent(const std::vector<double>& u, const std::vector<double>& v, double* jv) const;

  /// How a repeated product at one state (every effect affine in the bond, no damage) visits the
  /// bonds: Auto (Gathered in 3D on families of 16 bonds and more, else PerBond), PerBond (each bond's
  /// dt_l = A xi_l + c dY_l + k formed) or Gathered (sums of per-particle records, no per-bond
  /// algebra). The answers agree to round-off; the choice is about speed (docs/performance.md).
  enum class ProductForm { Auto, PerBond, Gathered };
  void setProductForm(ProductForm f);

  /// Adds the diagonal of df_int/du, summed over the owned elements, to d (local particles *
  /// dim, interleaved): the element tangents' diagonal blocks only, O(family) work per element
  /// instead of O(family^2) (Jacobi scaling of smoothers on the matrix-free Jacobian).
  void addJacobianDiagonal(const std::vector<double>& u, double* d) const;

  /// F and Cauchy stress of the owned particles at u (from the committed state), with the
  /// equivalent plastic strain and yield flag of the committed state.
  std::vector<ParticleOutput> outputs(const std::vector<double>& u) const;

  // ---- History (materials with internal variables) ---------------------------------------------
  // Every evaluation (residual, tangent, J v, diagonal) is a pure function of (u, committed
  // state): it computes the trial state of each point from the committed one and keeps nothing.
  // The committed state advances only through commitState.
  /// Whether some material has history (otherwise no state is held and commitState does nothing).
  bool hasHistory() const { return stateStride_ > 0; }
  /// Doubles per evaluation point (the largest stateSize of the materials) and points per
  /// particle (2 with stress points, else 1); a particle's block is their product.
  int stateStride() const { return stateStride_; }
  int statePointsPerParticle() const { return statePoints_; }
  int stateDoublesPerParticle() const { return stateStride_ * statePoints_; }
  /// The committed state of owned particle i (its points one after the other), nullptr without history.
  const double* committedState(int ownedLocal) const {
    return stateStride_ > 0 ? state_.data() + static_cast<std::size_t>(ownedLocal) * stateStride_ * statePoints_ : nullptr;
  }
  /// Makes the trial state at u (local displacements, as evaluate) the committed one: what a
  /// load stepper does once per accepted step, and what a host driving the model itself calls.
  /// Throws EvaluationError where the state cannot be evaluated (then nothing is committed).
  void commitState(const std::vector<double>& u);
  /// The committed states of the owned particles, in owned order (checkpoints), and its inverse.
  const std::vector<double>& committedStates() const { return state_; }
  void setCommittedStates(const std::vector<double>& s);

  /// Keeps only the bonds (i_local, j_local) for which keep returns true.
  template <class Pred>
  void removeBondsIf(Pred keep);
  void familiesChanged();  // drops the kept linearisation of the matrix-free product

 struct Impl;  // dimension-specific implementation (Model.cpp)

 private:
  /// Stretch (|Y| - |xi|) / |xi| of the bond from local particle i to local particle j at u.
  double bondStretch(const std::vector<double>& u, int i, int j) const;
  /// Breaks every bond that its damage law's stretch criterion, or (with eqps, the local
  /// particles' plastic strains) its ductile criterion, breaks; returns them counted once.
  long long breakBondsWhere(const std::vector<double>& u, const std::vector<double>* eqps);
  void checkShapeTensors() const;
  bool shapeTensorInvertible(int ownedLocal) const;
  std::optional<DamageSpec> damage_;
  std::vector<DamageSpec> damageLaws_;  // per material when enableDamage got a table
  std::vector<double> familyVolume0_;   // initial sum of V_j per owned particle
  std::vector<char> detached_;          // per owned particle
  std::vector<Material> materials_;
  LocalParticles particles_;
  std::unique_ptr<Impl> impl_;
  void initHistory();
  int stateStride_ = 0;
  int statePoints_ = 1;
  std::vector<double> state_;  // committed, per owned particle, per point
};

template <class Pred>
void Model::removeBondsIf(Pred keep) {
  std::vector<std::int64_t> off(1, 0);
  std::vector<int> idx;
  idx.reserve(particles_.famIndex.size());
  for (int i = 0; i < particles_.numOwned; ++i) {
    for (auto p = particles_.famOffset[i]; p < particles_.famOffset[i + 1]; ++p)
      if (keep(i, particles_.famIndex[p])) idx.push_back(particles_.famIndex[p]);
    off.push_back(static_cast<std::int64_t>(idx.size()));
  }
  particles_.famOffset.swap(off);
  particles_.famIndex.swap(idx);
  familiesChanged();
}

}  // namespace perinox
