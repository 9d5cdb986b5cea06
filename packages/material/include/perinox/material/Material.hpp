#pragma once
// Pointwise elastic materials for the correspondence model: first Piola-Kirchhoff stress P(F)
// and its tangent A = dP/dF, in the dimension of the model (1, 2 or 3). No MPI, no Trilinos.
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

/// Isotropic elastic constants plus the kinematic assumptions of the model.
struct MaterialSpec {
  MaterialKind kind = MaterialKind::Hencky;
  int dim = 2;
  PlanarMode planar = PlanarMode::PlaneStrain;
  double E = 1.0;   // Young's modulus
  double nu = 0.0;  // Poisson's ratio, -1 < nu < 0.5
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
  template <int D>
  bool stress(const MatD<D>& F, MatD<D>& P) const;

  /// Stress and tangent A = dP/dF (exact, including equal and nearly equal principal stretches).
  template <int D>
  bool stressTangent(const MatD<D>& F, MatD<D>& P, TangentD<D>& A) const;

  /// Full 3x3 Cauchy stress for output (plane strain has sigma_33 != 0; plane stress 0;
  /// 1D only sigma_11). Returns false under the same conditions as stress().
  template <int D>
  bool cauchy(const MatD<D>& F, Eigen::Matrix3d& sigma) const;

 private:
  MaterialSpec spec_;
  double lambda_;     // effective lambda of the reduced model (plane stress uses 2 lambda mu/(lambda+2 mu))
  double mu_;
  double lambda3d_;   // the 3D lambda, for the out-of-plane stress in plane strain
};

}  // namespace perinox
