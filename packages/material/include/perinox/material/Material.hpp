#pragma once
// Pointwise materials for the correspondence model: first Piola-Kirchhoff stress P(F) and its
// tangent A = dP/dF, in the dimension of the model (1, 2 or 3); elastic, or elastic-plastic (J2)
// with internal variables per point. No MPI, no Trilinos.
//
// Conventions
//  - F, P are D x D (D = model dimension). 2D is plane strain (F33 = 1) or plane stress
//    (F33 follows from tau33 = 0); 1D is uniaxial stress (a bar: sigma = E * strain).
//  - The tangent is stored flattened row-major: A(a*D + b, c*D + d) = dP_ab / dF_cd.
//  - Units: whatever the scene uses (stress in the units of E).
#include <Eigen/Dense>
#include <memory>
#include <string>

namespace perinox {

enum class MaterialKind { Hencky, SmallStrain };
enum class PlanarMode { PlaneStrain, PlaneStress, None };  // None for 1D and 3D

/// J2 (von Mises) plasticity with isotropic hardening. The yield stress as a function of the
/// equivalent plastic strain alpha is
///   sigma_y(alpha) = sigma_y0 + H alpha + (sigma_inf - sigma_y0) (1 - exp(-delta alpha)),
/// linear hardening (H), Voce saturation (sigma_inf, delta) or both; H = 0 without Voce is perfect
/// plasticity. With MaterialKind::Hencky the model is multiplicative (F = Fe Fp, Hencky elastic
/// law, von Mises yield on the Kirchhoff stress, flow integrated by the exponential map: a radial
/// return in principal logarithmic strains, det Fp = 1 exactly); with SmallStrain it is the
/// additive small-strain model (eps = eps_e + eps_p).
struct PlasticitySpec {
  bool enabled = false;
  double yieldStress = 0.0;       // sigma_y0 > 0
  double hardeningModulus = 0.0;  // H >= 0
  bool voce = false;
  double saturationStress = 0.0;  // sigma_inf >= sigma_y0 (Voce)
  double saturationRate = 0.0;    // delta > 0 (Voce)
  double yield(double alpha) const;
  double slope(double alpha) const;  // d sigma_y / d alpha
};

/// Isotropic elastic constants plus the kinematic assumptions of the model.
struct MaterialSpec {
  MaterialKind kind = MaterialKind::Hencky;
  int dim = 2;
  PlanarMode planar = PlanarMode::PlaneStrain;
  double E = 1.0;   // Young's modulus
  double nu = 0.0;  // Poisson's ratio, -1 < nu < 0.5
  PlasticitySpec plastic{};  // off: elastic (braces: aggregate initialisers may leave it out without a warning)
};

template <int D>
using MatD = Eigen::Matrix<double, D, D>;
template <int D>
using TangentD = Eigen::Matrix<double, D * D, D * D>;

/// Lame constants of a spec (lambda, mu) before any planar reduction.
double lameLambda(const MaterialSpec& s);
double lameMu(const MaterialSpec& s);

class Material {
 public:
  explicit Material(const MaterialSpec& spec);

  const MaterialSpec& spec() const { return spec_; }
  /// Lame lambda of the reduced model (plane stress: 2 lambda mu / (lambda + 2 mu)), and mu.
  double lambdaEff() const { return lambda_; }
  double mu() const { return mu_; }

  /// First Piola-Kirchhoff stress P(F). Returns false (and leaves P untouched) when
  /// det F <= 0 or F is not finite: the caller reports that, never silently continues.
  /// A plastic material is evaluated here from its virgin state.
  template <int D>
  bool stress(const MatD<D>& F, MatD<D>& P) const;

  /// Stress and tangent A = dP/dF (exact, including equal and nearly equal principal stretches).
  template <int D>
  bool stressTangent(const MatD<D>& F, MatD<D>& P, TangentD<D>& A) const;

  /// Full 3x3 Cauchy stress for output (plane strain has sigma_33 != 0; plane stress 0;
  /// 1D only sigma_11). Returns false under the same conditions as stress().
  template <int D>
  bool cauchy(const MatD<D>& F, Eigen::Matrix3d& sigma) const;

  // ---- Materials with history (plasticity) ----------------------------------------------------
  // The state of a point is stateSize() doubles. The evaluation is a pure function of F and the
  // committed state: it writes the trial state (the state a commit at this F would keep) into
  // `trial` when that is not null, and never touches `committed`. `committed` may be null (the
  // virgin state); `trial` may alias `committed` (everything is read before anything is written).
  // For an elastic material stateSize() is 0 and both pointers are ignored.
  // The tangent is the algorithmic (consistent) one of the return map.
  bool plastic() const { return spec_.plastic.enabled; }
  /// Doubles per point: 1D 3, plane strain 6, plane stress 7, 3D 8; elastic 0.
  int stateSize() const { return stateSize_; }
  /// The virgin state: no plastic strain.
  void initialState(double* s) const;
  /// Equivalent plastic strain alpha of a state (0 for an elastic material or a null state).
  double equivalentPlasticStrain(const double* state) const;
  /// Whether the step that produced this state flowed plastically (the point is on the yield surface).
  bool yielding(const double* state) const;

  template <int D>
  bool stress(const MatD<D>& F, const double* committed, MatD<D>& P, double* trial) const;
  template <int D>
  bool stressTangent(const MatD<D>& F, const double* committed, MatD<D>& P, TangentD<D>& A, double* trial) const;
  template <int D>
  bool cauchy(const MatD<D>& F, const double* committed, Eigen::Matrix3d& sigma) const;

 private:
  MaterialSpec spec_;
  double lambda_;     // effective lambda of the reduced model (plane stress uses 2 lambda mu/(lambda+2 mu))
  double mu_;
  double lambda3d_;   // the 3D lambda, for the out-of-plane stress in plane strain
  int stateSize_ = 0;
  template <int D>
  bool plasticEval(const MatD<D>& F, const double* committed, MatD<D>& P, TangentD<D>* A, double* trial,
                   Eigen::Matrix3d* sigma) const;
};

}  // namespace perinox
