// Pointwise elastic materials: Hencky (logarithmic strain, finite deformation) and linear
// small-strain elasticity, in 1, 2 (plane strain / plane stress) and 3 dimensions.
//
// Hencky, in the reduced dimension N (2 or 3) with effective Lame constants (lambda, mu):
//   b = F F^T,  eps = 1/2 ln b,  tau = lambda tr(eps) I + 2 mu eps,  P = tau F^{-T}.
// The tangent A = dP/dF uses the Daleckii-Krein formula for the derivative of the matrix
// logarithm in the eigenbasis of b, with a cancellation-free divided difference of ln so that
// equal and nearly equal principal stretches are exact (see logDividedDifference).
//
// Everything here works on fixed-size Eigen objects on the stack: no heap allocation, no
// virtual calls; this runs for every particle in every Newton iteration.
#include "perinox/material/Material.hpp"

#include "LawKernels.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace perinox {

double lameLambda(const MaterialSpec& s) { return s.E * s.nu / ((1.0 + s.nu) * (1.0 - 2.0 * s.nu)); }
double lameMu(const MaterialSpec& s) { return s.E / (2.0 * (1.0 + s.nu)); }

namespace {

using detail::logDividedDifference;
using detail::smallStrainTangent;
using detail::throwDimMismatch;
using detail::SymEig;
using detail::symEig;
template <int N>
using Vec = detail::Vec<N>;

/// Kinematics and Kirchhoff stress of Hencky elasticity in dimension N (2 or 3).
template <int N>
struct HenckyState {
  SymEig<N> eig;
  MatD<N> tau;  // Kirchhoff stress (stress units)
  MatD<N> G;    // F^{-T}
  double J;     // det F (of the N x N block)
};

/// Fills s from F. False when F is not finite or det F <= 0 (then s is unspecified).
/// tr(eps) = 1/2 ln det b = ln J is taken from J directly: accurate to roundoff and free of
/// eigen solver error.
template <int N>
bool henckyKirchhoff(const MatD<N>& F, double lambda, double mu, HenckyState<N>& s) {
  if (!F.allFinite()) return false;
  s.J = F.determinant();
  if (!(s.J > 0.0)) return false;
  const MatD<N> b = F * F.transpose();
  if (!symEig(b, s.J * s.J, s.eig)) return false;
  const Vec<N> halfLog = 0.5 * s.eig.l.array().log().matrix();
  const MatD<N> eps = s.eig.Q * halfLog.asDiagonal() * s.eig.Q.transpose();
  s.tau = (2.0 * mu) * eps;
  s.tau.diagonal().array() += lambda * std::log(s.J);
  s.G = F.inverse().transpose();
  return true;
}

/// A = dP/dF, column c*N+d = dP for dF = e_c e_d^T:
///   db   = dF F^T + F dF^T;   in the eigenbasis  db~ = Q^T db Q = q_c f_d^T + f_d q_c^T,
///          q_c = Q^T e_c (row c of Q), f_d = Q^T F e_d (column d of Q^T F);
///   deps = 1/2 Q (g o db~) Q^T,  g_ab = divided difference of ln at (l_a, l_b)  (Daleckii-Krein);
///   tr(deps) = d ln J = tr(F^{-1} dF) = G_cd;
///   dtau = lambda tr(deps) I + 2 mu deps;
///   dP   = dtau G - tau G dF^T G = dtau G - (tau G e_d)(e_c^T G).
/// With W = Q^T G and g o (q f^T) = diag(q) g diag(f), the deviatoric part of dtau G is
///   Q (g o db~) W = Q [diag(q_c) U_d + diag(f_d) V_c],  U_d = g diag(f_d) W,  V_c = g diag(q_c) W,
/// so the 2N products U_d, V_c are shared by all N^2 columns, each of which then costs a single
/// N x N product (about half the work of forming dtau and multiplying by G per column).
template <int N>
void henckyTangent(const MatD<N>& F, double lambda, double mu, const HenckyState<N>& s,
                   TangentD<N>& A) {
  const MatD<N>& Q = s.eig.Q;
  MatD<N> g;  // symmetric weights, with the 1/2 of eps = 1/2 ln b and the 2 mu folded in
  for (int a = 0; a < N; ++a) {
    g(a, a) = mu / s.eig.l(a);
    for (int b = a + 1; b < N; ++b) g(a, b) = g(b, a) = mu * logDividedDifference(s.eig.l(a), s.eig.l(b));
  }
  const MatD<N> QtF = Q.transpose() * F;  // column d is f_d
  const MatD<N> W = Q.transpose() * s.G;
  const MatD<N> tauG = s.tau * s.G;
  MatD<N> U[N], V[N];
  for (int k = 0; k < N; ++k) {
    U[k] = g * QtF.col(k).asDiagonal() * W;
    V[k] = g * Q.row(k).asDiagonal() * W;
  }
  for (int c = 0; c < N; ++c) {
    for (int d = 0; d < N; ++d) {
      const MatD<N> M = Q.row(c).asDiagonal() * U[d] + QtF.col(d).asDiagonal() * V[c];
      const MatD<N> dP = Q * M + (lambda * s.G(c, d)) * s.G - tauG.col(d) * s.G.row(c);
      for (int a = 0; a < N; ++a)
        for (int b = 0; b < N; ++b) A(a * N + b, c * N + d) = dP(a, b);
    }
  }
}

/// Linear elasticity: sigma = lambda tr(eps) I + 2 mu eps with eps = sym(F) - I.
template <int N>
MatD<N> smallStrainStress(const MatD<N>& F, double lambda, double mu) {
  const MatD<N> eps = 0.5 * (F + F.transpose()) - MatD<N>::Identity();
  MatD<N> sigma = (2.0 * mu) * eps;
  sigma.diagonal().array() += lambda * eps.trace();
  return sigma;
}

}  // namespace

Material::Material(const MaterialSpec& spec) : spec_(spec) {
  if (!(spec.E > 0.0) || !std::isfinite(spec.E))
    throw std::invalid_argument("perinox::Material: Young's modulus E must be positive and finite (got " +
                                std::to_string(spec.E) + ").");
  if (!(spec.nu > -1.0 && spec.nu < 0.5))
    throw std::invalid_argument("perinox::Material: Poisson's ratio nu must satisfy -1 < nu < 0.5 (got " +
                                std::to_string(spec.nu) + ").");
  if (spec.dim < 1 || spec.dim > 3)
    throw std::invalid_argument("perinox::Material: dimension must be 1, 2 or 3 (got " +
                                std::to_string(spec.dim) + ").");
  if (spec.dim == 2 && spec.planar == PlanarMode::None)
    throw std::invalid_argument(
        "perinox::Material: a 2D material needs a planar mode, PlaneStrain or PlaneStress (got None).");
  // 1D and 3D have no planar reduction: the planar field is ignored there (its default value is
  // PlaneStrain, so rejecting it would only punish callers who did not touch it).
  if (spec.dim != 2) spec_.planar = PlanarMode::None;

  const PlasticitySpec& pl = spec_.plastic;
  if (pl.enabled) {
    auto bad = [](const std::string& what) {
      throw std::invalid_argument("perinox::Material: " + what);
    };
    if (!(pl.yieldStress > 0.0) || !std::isfinite(pl.yieldStress))
      bad("the yield stress must be positive and finite (got " + std::to_string(pl.yieldStress) + ").");
    if (!(pl.hardeningModulus >= 0.0) || !std::isfinite(pl.hardeningModulus))
      bad("the hardening modulus must be zero or positive and finite (got " + std::to_string(pl.hardeningModulus) + ").");
    if (pl.voce && (!(pl.saturationStress >= pl.yieldStress) || !std::isfinite(pl.saturationStress)))
      bad("the Voce saturation stress must be finite and at least the yield stress (got " +
          std::to_string(pl.saturationStress) + " against " + std::to_string(pl.yieldStress) + ").");
    if (pl.voce && (!(pl.saturationRate > 0.0) || !std::isfinite(pl.saturationRate)))
      bad("the Voce saturation rate must be positive and finite (got " + std::to_string(pl.saturationRate) + ").");
    stateSize_ = spec_.dim == 1 ? 3 : spec_.dim == 3 ? 8 : spec_.planar == PlanarMode::PlaneStress ? 7 : 6;
  }

  lambda3d_ = lameLambda(spec_);
  mu_ = lameMu(spec_);
  lambda_ = spec_.planar == PlanarMode::PlaneStress ? 2.0 * lambda3d_ * mu_ / (lambda3d_ + 2.0 * mu_)
                                                    : lambda3d_;
}

template <int D>
bool Material::stress(const MatD<D>& F, MatD<D>& P) const {
  if (D != spec_.dim) throwDimMismatch(D, spec_.dim);
  if (spec_.plastic.enabled) return plasticEval<D>(F, nullptr, P, nullptr, nullptr, nullptr);
  if (spec_.kind == MaterialKind::SmallStrain) {
    if (!F.allFinite()) return false;
    if constexpr (D == 1) {
      P(0, 0) = spec_.E * (F(0, 0) - 1.0);
    } else {
      P = smallStrainStress<D>(F, lambda_, mu_);
    }
    return true;
  }
  if constexpr (D == 1) {
    // Uniaxial bar: Kirchhoff tau = E ln(stretch), P = tau / stretch.
    const double f = F(0, 0);
    if (!std::isfinite(f) || !(f > 0.0)) return false;
    P(0, 0) = spec_.E * std::log(f) / f;
    return true;
  } else {
    HenckyState<D> s;
    if (!henckyKirchhoff<D>(F, lambda_, mu_, s)) return false;
    P = s.tau * s.G;
    return true;
  }
}

template <int D>
bool Material::stressTangent(const MatD<D>& F, MatD<D>& P, TangentD<D>& A) const {
  if (D != spec_.dim) throwDimMismatch(D, spec_.dim);
  if (spec_.plastic.enabled) return plasticEval<D>(F, nullptr, P, &A, nullptr, nullptr);
  if (spec_.kind == MaterialKind::SmallStrain) {
    if (!F.allFinite()) return false;
    if constexpr (D == 1) {
      P(0, 0) = spec_.E * (F(0, 0) - 1.0);
      A(0, 0) = spec_.E;
    } else {
      P = smallStrainStress<D>(F, lambda_, mu_);
      smallStrainTangent<D>(lambda_, mu_, A);
    }
    return true;
  }
  if constexpr (D == 1) {
    // d/df (E ln f / f) = E (1 - ln f) / f^2.
    const double f = F(0, 0);
    if (!std::isfinite(f) || !(f > 0.0)) return false;
    const double lf = std::log(f);
    P(0, 0) = spec_.E * lf / f;
    A(0, 0) = spec_.E * (1.0 - lf) / (f * f);
    return true;
  } else {
    HenckyState<D> s;
    if (!henckyKirchhoff<D>(F, lambda_, mu_, s)) return false;
    P = s.tau * s.G;
    henckyTangent<D>(F, lambda_, mu_, s, A);
    return true;
  }
}

template <int D>
bool Material::cauchy(const MatD<D>& F, Eigen::Matrix3d& sigma) const {
  if (D != spec_.dim) throwDimMismatch(D, spec_.dim);
  if (spec_.plastic.enabled) {
    MatD<D> P;
    return plasticEval<D>(F, nullptr, P, nullptr, nullptr, &sigma);
  }
  // sigma is written only on success, like P in stress().
  if (spec_.kind == MaterialKind::SmallStrain) {
    if (!F.allFinite()) return false;
    sigma.setZero();
    if constexpr (D == 1) {
      sigma(0, 0) = spec_.E * (F(0, 0) - 1.0);
    } else {
      sigma.template topLeftCorner<D, D>() = smallStrainStress<D>(F, lambda_, mu_);
      // Plane strain: sigma33 = lambda tr(eps) = nu (sigma11 + sigma22). Plane stress: 0.
      if (D == 2 && spec_.planar == PlanarMode::PlaneStrain) sigma(2, 2) = lambda3d_ * (F(0, 0) + F(1, 1) - 2.0);
    }
    return true;
  }
  if constexpr (D == 1) {
    // The bar model carries no lateral kinematics: J = stretch, sigma11 = tau / stretch.
    const double f = F(0, 0);
    if (!std::isfinite(f) || !(f > 0.0)) return false;
    sigma.setZero();
    sigma(0, 0) = spec_.E * std::log(f) / f;
    return true;
  } else {
    HenckyState<D> s;
    if (!henckyKirchhoff<D>(F, lambda_, mu_, s)) return false;
    sigma.setZero();
    if constexpr (D == 3) {
      sigma = s.tau / s.J;
    } else if (spec_.planar == PlanarMode::PlaneStrain) {
      // F33 = 1: J = det2 F, eps33 = 0, tau33 = lambda tr(eps) = lambda ln J.
      sigma.topLeftCorner<2, 2>() = s.tau / s.J;
      sigma(2, 2) = lambda3d_ * std::log(s.J) / s.J;
    } else {
      // Plane stress: tau33 = 0 gives eps33 = -lambda/(lambda + 2 mu) ln(det2 F) (3D lambda),
      // F33 = exp(eps33), J = det2 F * F33; sigma33 = 0.
      const double eps33 = -lambda3d_ / (lambda3d_ + 2.0 * mu_) * std::log(s.J);
      const double J = s.J * std::exp(eps33);
      sigma.topLeftCorner<2, 2>() = s.tau / J;
    }
    return true;
  }
}

#define PERINOX_MATERIAL_INSTANTIATE(D)                                                          \
  template bool Material::stress<D>(const MatD<D>&, MatD<D>&) const;                             \
  template bool Material::stressTangent<D>(const MatD<D>&, MatD<D>&, TangentD<D>&) const;        \
  template bool Material::cauchy<D>(const MatD<D>&, Eigen::Matrix3d&) const;

PERINOX_MATERIAL_INSTANTIATE(1)
PERINOX_MATERIAL_INSTANTIATE(2)
PERINOX_MATERIAL_INSTANTIATE(3)

#undef PERINOX_MATERIAL_INSTANTIATE

}  // namespace perinox
