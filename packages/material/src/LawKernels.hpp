#pragma once
// Kernels shared by the elastic and the elastic-plastic laws (internal to the material package):
// the divided difference of ln, the eigen decomposition of a symmetric positive definite 2x2 or
// 3x3 matrix, the isotropic small-strain tangent, and the dimension check.
#include "perinox/material/Material.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace perinox::detail {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

/// (ln lb - ln la) / (lb - la) for la, lb > 0, and 1/la when la == lb: the first divided
/// difference of ln, i.e. the Daleckii-Krein weight of the matrix logarithm. The naive
/// quotient loses all digits as lb -> la. With the larger value as reference,
/// x = (lb - la)/la lies in (-1, 0] and the quotient is log1p(x) / (x la), accurate to a few
/// ulps for any x != 0; for |x| < 1e-5 the Taylor series of log1p(x)/x truncated after x^3
/// has a relative error below x^4/5 < 2e-21, so x == 0 (equal eigenvalues) is exact too.
/// Symmetric in (la, lb) by construction, which keeps the tangent's major symmetry.
inline double logDividedDifference(double la, double lb) {
  if (la < lb) std::swap(la, lb);
  const double x = (lb - la) / la;  // exact subtraction when lb/la is in [1/2, 1] (Sterbenz)
  if (std::abs(x) < 1e-5) return (1.0 - x * (0.5 - x * (1.0 / 3.0 - 0.25 * x))) / la;
  return std::log1p(x) / (x * la);
}

/// Eigen decomposition b = Q diag(l) Q^T of a symmetric positive definite matrix.
template <int N>
struct SymEig {
  MatD<N> Q;
  Vec<N> l;
};

/// 2x2 closed form. With m = (b00 + b11)/2, h = (b00 - b11)/2, c = b01 and r = hypot(h, c):
/// l0 = m + r (no cancellation, m > 0, r >= 0) and l1 = det(b)/l0, where det(b) = J^2 comes from
/// det F (no squared-stretch cancellation), so the small eigenvalue stays accurate however stretched F is. The
/// eigenvector of l0 is (cos t, sin t) with t = atan2(c, h)/2; for equal eigenvalues (h = c = 0)
/// atan2(0, 0) = 0 gives Q = I, a valid basis, with no special case needed.
inline bool symEig(const MatD<2>& b, double detb, SymEig<2>& e) {
  const double m = 0.5 * (b(0, 0) + b(1, 1));
  const double h = 0.5 * (b(0, 0) - b(1, 1));
  const double c = 0.5 * (b(0, 1) + b(1, 0));
  const double r = std::hypot(h, c);
  e.l(0) = m + r;
  e.l(1) = detb / e.l(0);
  const double t = 0.5 * std::atan2(c, h);
  const double ct = std::cos(t), st = std::sin(t);
  e.Q << ct, -st, st, ct;
  return e.l(1) > 0.0 && std::isfinite(e.l(0));
}

/// 3x3: Eigen's tridiagonal QR iteration (fixed size, no heap). The closed-form computeDirect
/// is ~300 ns cheaper but not accurate enough for a Newton tangent: measured against a
/// long-double reference, the error of ln(b) reached 2e-8 for principal stretches in [1/2, 2]
/// and 5e-6 in [1/10, 10], against 2e-15 and 2e-13 with the QR iteration.
inline bool symEig(const MatD<3>& b, double /*detb*/, SymEig<3>& e) {
  Eigen::SelfAdjointEigenSolver<MatD<3>> es(b, Eigen::ComputeEigenvectors);
  if (es.info() != Eigen::Success) return false;
  e.Q = es.eigenvectors();
  e.l = es.eigenvalues();
  // Extreme stretch (condition number of F beyond ~1e8) can round the smallest eigenvalue of b
  // to <= 0; report failure instead of taking the log of it.
  return e.l.minCoeff() > 0.0 && e.l.allFinite();
}

/// A(ab,cd) = lambda d_ab d_cd + mu (d_ac d_bd + d_ad d_bc).
template <int N>
inline void smallStrainTangent(double lambda, double mu, TangentD<N>& A) {
  A.setZero();
  for (int a = 0; a < N; ++a) {
    for (int b = 0; b < N; ++b) {
      A(a * N + b, b * N + a) += mu;
      A(a * N + b, a * N + b) += mu;
    }
    for (int c = 0; c < N; ++c) A(a * N + a, c * N + c) += lambda;
  }
}

[[noreturn]] inline void throwDimMismatch(int D, int dim) {
  throw std::logic_error("perinox::Material: called with a " + std::to_string(D) +
                         "D deformation gradient but the material was built for dim = " +
                         std::to_string(dim) + ".");
}

}  // namespace perinox::detail
