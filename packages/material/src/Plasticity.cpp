// J2 (von Mises) plasticity with isotropic hardening, at finite strain (multiplicative, Hencky
// elastic law, exponential-map flow) and at small strain (additive), in 1D (uniaxial stress),
// plane strain, plane stress and 3D, with the algorithmic (consistent) tangent.
//
// Finite strain, 3D. The state holds c = Cp^{-1} (symmetric, det c = 1) and alpha. For a given F
// the trial elastic left Cauchy-Green tensor is be = F c F^T = Q diag(l) Q^T with principal
// logarithmic strains e_a = 1/2 ln l_a, volumetric part tr = ln J + 1/2 ln det c and deviatoric
// part d = e - mean(e). The trial Mises stress is q = sqrt(6) mu |d|. When q > sigma_y(alpha) the
// return solves  q - 3 mu x - sigma_y(alpha + x) = 0  for the plastic multiplier x (the increment
// of equivalent plastic strain) and scales the deviator by theta = 1 - 3 mu x / q:
//   tau_a = kappa tr + 2 mu theta d_a,    P = tau F^{-T},
// and the new state is be_new = Q diag(l_a exp(-2 (1 - theta) d_a)) Q^T, c_new = F^{-1} be_new F^{-T}
// (a traceless update in log space, so det c is kept exactly), alpha_new = alpha + x.
// The algorithmic tangent of tau with respect to the trial log strain eps = 1/2 ln be is
//   dtau = kappa tr(deps) I + 2 mu theta dev(deps) + cN (n : deps) n,
//   cN = 6 mu^2 (x / q - 1 / (3 mu + H')),  n = d / |d|,  H' = sigma_y'(alpha + x),
// and deps follows from dbe by the Daleckii-Krein formula, as for the elastic law.
//
// Small strain: the same return on eps - eps_p with eps = sym(F) - I; eps_p += (1 - theta) dev(eps_e).
// Plane strain embeds F in 3D with F33 = 1. Plane stress solves P33 = 0 for F33 inside the
// evaluation (safeguarded Newton on the 3D tangent, started from the committed F33) and condenses
// the tangent: A2 = A(ab, cd) - A(ab, 33) A(33, cd) / A(33, 33).
#include "perinox/material/Material.hpp"

#include "LawKernels.hpp"

#include <cmath>
#include <limits>

namespace perinox {

double PlasticitySpec::yield(double alpha) const {
  double s = yieldStress + hardeningModulus * alpha;
  if (voce) s -= (saturationStress - yieldStress) * std::expm1(-saturationRate * alpha);
  return s;
}

double PlasticitySpec::slope(double alpha) const {
  double h = hardeningModulus;
  if (voce) h += (saturationStress - yieldStress) * saturationRate * std::exp(-saturationRate * alpha);
  return h;
}

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using Mat9 = Eigen::Matrix<double, 9, 9>;

/// Result of the scalar return: x is the plastic multiplier, slope = sigma_y'(alpha + x).
struct ScalarReturn {
  bool active = false;
  double x = 0.0;
  double slope = 0.0;
};

/// Solves q - M x - sigma_y(alpha + x) = 0 for x >= 0 when q exceeds sigma_y(alpha). The
/// function is decreasing (slope -M - H' < 0) and convex (sigma_y is concave), so Newton from
/// x = 0 increases monotonically to the root: no overshoot, no safeguard needed. Linear
/// hardening converges in one step. False only for non-finite data.
/// A point within kYieldTolerance of the surface is elastic: re-evaluated at the F it was
/// committed at, a point that flowed lies on the surface up to round-off (f ~ +-1e-15 sigma_y),
/// and taking those as plastic would give a plastic tangent to about half of them at random at
/// the start of the next step (an unloading step's Newton then cycles between the active sets).
constexpr double kYieldTolerance = 1e-10;

bool scalarReturn(const PlasticitySpec& p, double q, double alpha, double M, ScalarReturn& r) {
  r = ScalarReturn{};
  const double sy = p.yield(alpha);
  const double f = q - sy;
  if (!std::isfinite(f)) return false;
  if (!(f > kYieldTolerance * sy)) return true;
  r.active = true;
  double x = 0.0;
  for (int it = 0; it < 60; ++it) {
    const double res = q - M * x - p.yield(alpha + x);
    const double dx = res / (M + p.slope(alpha + x));
    x += dx;
    if (!std::isfinite(x)) return false;
    if (std::abs(res) <= 1e-15 * q || std::abs(dx) <= 1e-15 * x) {
      r.x = x;
      r.slope = p.slope(alpha + x);
      return true;
    }
  }
  return false;
}

/// The radial return of a 3D deviator d (log strain or strain) with Mises stress q = sqrt(6) mu |d|:
/// the deviator is scaled by theta, and the consistent tangent gains cN (n : deps) n, n = d / |d|.
struct Radial {
  ScalarReturn r;
  double theta = 1.0;
  double cN = 0.0;
};

bool radialReturn(const PlasticitySpec& p, double q, double alpha, double mu, Radial& out) {
  out = Radial{};
  if (!scalarReturn(p, q, alpha, 3.0 * mu, out.r)) return false;
  if (out.r.active) {
    out.theta = 1.0 - 3.0 * mu * out.r.x / q;
    out.cN = 6.0 * mu * mu * (out.r.x / q - 1.0 / (3.0 * mu + out.r.slope));
  }
  return true;
}

/// One 3D material point: Kirchhoff stress (finite) or Cauchy stress (small strain) in `tau`,
/// P, J = det F, and the trial state [c or eps_p (11,12,13,22,23,33), alpha, active].
struct Point3 {
  Mat3 tau;
  Mat3 P;
  double J = 1.0;
  double state[8];
};

Mat3 symFrom6(const double* s) {
  Mat3 m;
  m << s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5];
  return m;
}

void symTo6(const Mat3& m, double* s) {
  s[0] = m(0, 0);
  s[1] = 0.5 * (m(0, 1) + m(1, 0));
  s[2] = 0.5 * (m(0, 2) + m(2, 0));
  s[3] = m(1, 1);
  s[4] = 0.5 * (m(1, 2) + m(2, 1));
  s[5] = m(2, 2);
}

/// The trial state [tensor (6), alpha, flag]: after flow, `flowed` (the new c or eps_p) and the
/// increased alpha; without flow, the committed tensor and alpha.
void writeState(const Radial& rr, const double* st, const Mat3& flowed, double* out) {
  if (rr.r.active) {
    symTo6(flowed, out);
    out[6] = st[6] + rr.r.x;
  } else {
    for (int k = 0; k < 7; ++k) out[k] = st[k];
  }
  out[7] = rr.r.active ? 1.0 : 0.0;
}

/// Finite-strain J2 at a 3D point. `st` is the committed state (8 doubles).
bool henckyJ2(const Mat3& F, const double* st, double kappa, double mu, const PlasticitySpec& p,
              Point3& out, Mat9* A) {
  if (!F.allFinite()) return false;
  const double J = F.determinant();
  if (!(J > 0.0)) return false;
  const Mat3 c = symFrom6(st);
  const double alpha = st[6];
  const double detc = c.determinant();
  if (!(detc > 0.0) || !std::isfinite(detc)) return false;
  const Mat3 Fc = F * c;
  Mat3 be = Fc * F.transpose();
  be = 0.5 * (be + be.transpose()).eval();
  detail::SymEig<3> eig;
  if (!detail::symEig(be, 0.0, eig)) return false;
  const Vec3 e = 0.5 * eig.l.array().log().matrix();
  const double tr = std::log(J) + 0.5 * std::log(detc);
  const Vec3 d = e.array() - e.sum() / 3.0;
  const double nd = d.norm();
  Radial rr;
  if (!radialReturn(p, std::sqrt(6.0) * mu * nd, alpha, mu, rr)) return false;
  const double theta = rr.theta;
  const Vec3 taup = (kappa * tr) + (2.0 * mu * theta) * d.array();
  const Mat3& Q = eig.Q;
  out.tau = Q * taup.asDiagonal() * Q.transpose();
  const Mat3 Finv = F.inverse();
  const Mat3 G = Finv.transpose();
  out.P = out.tau * G;
  out.J = J;
  Mat3 cnew = c;
  if (rr.r.active) {
    const Vec3 lnew = eig.l.array() * (-2.0 * (1.0 - theta) * d.array()).exp();
    cnew = Finv * (Q * lnew.asDiagonal() * Q.transpose()) * Finv.transpose();
  }
  writeState(rr, st, cnew, out.state);
  if (A) {
    // dF = e_c e_d^T: dbe~ = q_c f_d^T + f_d q_c^T (q_c = row c of Q, f_d = column d of Q^T F c),
    // deps~ = 1/2 g o dbe~, tr(deps) = d ln J = G(c, d); dP = dtau G - (tau G e_d)(e_c^T G).
    Mat3 g;
    for (int a = 0; a < 3; ++a) {
      g(a, a) = 0.5 / eig.l(a);
      for (int b = a + 1; b < 3; ++b) g(a, b) = g(b, a) = 0.5 * detail::logDividedDifference(eig.l(a), eig.l(b));
    }
    const Vec3 n = rr.r.active ? Vec3(d / nd) : Vec3::Zero();
    const Mat3 QtFc = Q.transpose() * Fc;
    const Mat3 tauG = out.tau * G;
    const double twoMuTheta = 2.0 * mu * theta;
    for (int cc = 0; cc < 3; ++cc) {
      const Vec3 qc = Q.row(cc).transpose();
      for (int dd = 0; dd < 3; ++dd) {
        const Vec3 fd = QtFc.col(dd);
        const Mat3 de = g.cwiseProduct(qc * fd.transpose() + fd * qc.transpose());
        const double trd = G(cc, dd);
        Mat3 dt = twoMuTheta * de;
        dt.diagonal().array() += (kappa - twoMuTheta / 3.0) * trd;
        if (rr.r.active) dt.diagonal() += (rr.cN * n.dot(de.diagonal())) * n;
        const Mat3 dP = Q * dt * Q.transpose() * G - tauG.col(dd) * G.row(cc);
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) (*A)(a * 3 + b, cc * 3 + dd) = dP(a, b);
      }
    }
  }
  return true;
}

/// Small-strain J2 at a 3D point: eps = sym(F) - I, state [eps_p (6), alpha, active].
bool smallJ2(const Mat3& F, const double* st, double kappa, double mu, const PlasticitySpec& p,
             Point3& out, Mat9* A) {
  if (!F.allFinite()) return false;
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  const Mat3 ee = eps - symFrom6(st);
  const double alpha = st[6];
  const double tr = ee.trace();
  const Mat3 dev = ee - (tr / 3.0) * Mat3::Identity();
  const double nd = dev.norm();
  Radial rr;
  if (!radialReturn(p, std::sqrt(6.0) * mu * nd, alpha, mu, rr)) return false;
  const double theta = rr.theta;
  out.tau = (2.0 * mu * theta) * dev;
  out.tau.diagonal().array() += kappa * tr;
  out.P = out.tau;
  out.J = 1.0;
  writeState(rr, st, symFrom6(st) + (1.0 - theta) * dev, out.state);
  if (A) {
    // The isotropic law with the scaled shear modulus mu theta (bulk modulus kappa kept), plus
    // cN N (x) N, N = dev / |dev|.
    detail::smallStrainTangent<3>(kappa - 2.0 * mu * theta / 3.0, mu * theta, *A);
    if (rr.r.active) {
      const Mat3 N = dev / nd;
      const Eigen::Map<const Eigen::Matrix<double, 9, 1>> n(N.data());  // N is symmetric: either order
      *A += rr.cN * n * n.transpose();
    }
  }
  return true;
}

}  // namespace

template <int D>
bool Material::plasticEval(const MatD<D>& F, const double* committed, MatD<D>& P, TangentD<D>* A,
                           double* trial, Eigen::Matrix3d* sigma) const {
  if (D != spec_.dim) detail::throwDimMismatch(D, spec_.dim);
  const PlasticitySpec& p = spec_.plastic;
  const bool finite = spec_.kind == MaterialKind::Hencky;
  double st[8];
  if (committed) {
    for (int k = 0; k < stateSize_; ++k) st[k] = committed[k];
  } else {
    initialState(st);
  }
  if constexpr (D == 1) {
    // Uniaxial stress: tau = E (e - eps_p), e = ln f (Hencky) or f - 1 (small strain).
    const double f = F(0, 0);
    if (!std::isfinite(f) || (finite && !(f > 0.0))) return false;
    const double E = spec_.E;
    const double e = finite ? std::log(f) : f - 1.0;
    const double tt = E * (e - st[0]);
    ScalarReturn r;
    if (!scalarReturn(p, std::abs(tt), st[1], E, r)) return false;
    const double sgn = tt < 0.0 ? -1.0 : 1.0;
    const double tau = tt - sgn * E * r.x;
    const double dtde = r.active ? E * r.slope / (E + r.slope) : E;
    P(0, 0) = finite ? tau / f : tau;
    if (A) (*A)(0, 0) = finite ? (dtde - tau) / (f * f) : dtde;
    if (sigma) {
      sigma->setZero();
      (*sigma)(0, 0) = finite ? tau / f : tau;
    }
    if (trial) {
      trial[0] = st[0] + sgn * r.x;
      trial[1] = st[1] + r.x;
      trial[2] = r.active ? 1.0 : 0.0;
    }
    return true;
  } else {
    const double kappa = lambda3d_ + 2.0 * mu_ / 3.0;
    auto point = [&](const Mat3& F3, const double* s3, Point3& out, Mat9* A3) {
      return finite ? henckyJ2(F3, s3, kappa, mu_, p, out, A3) : smallJ2(F3, s3, kappa, mu_, p, out, A3);
    };
    Point3 pt;
    if constexpr (D == 3) {
      Mat9 A3;
      if (!point(F, st, pt, A ? &A3 : nullptr)) return false;
      P = pt.P;
      if (A) *A = A3;
      if (sigma) *sigma = finite ? Mat3(pt.tau / pt.J) : pt.tau;
      if (trial)
        for (int k = 0; k < 8; ++k) trial[k] = pt.state[k];
      return true;
    } else {
      // 2D state [s11, s12, s22, s33, alpha, active (, F33 for plane stress)] embedded in 3D.
      const double s3[8] = {st[0], st[1], 0.0, st[2], 0.0, st[3], st[4], st[5]};
      if (!F.allFinite()) return false;
      Mat3 F3 = Mat3::Zero();
      F3.topLeftCorner<2, 2>() = F;
      Mat9 A3;
      double z = 1.0;
      if (spec_.planar == PlanarMode::PlaneStrain) {
        F3(2, 2) = 1.0;
        if (!point(F3, s3, pt, A ? &A3 : nullptr)) return false;
      } else {
        // Plane stress: P33(z) = 0 with z = F33. P33 increases with z (A(33,33) > 0), so a
        // Newton step that leaves the bracket [lo, hi] known so far is replaced by bisection
        // (or by doubling while no upper bound is known).
        z = st[6];
        double lo = 0.0, hi = std::numeric_limits<double>::infinity();
        bool converged = false;
        for (int it = 0; it < 100; ++it) {
          F3(2, 2) = z;
          if (!point(F3, s3, pt, &A3)) {
            // det F3 <= 0 or a failed return: step back towards the lower bound.
            if (!(z > lo)) return false;
            hi = z;
            z = 0.5 * (lo + hi);
            continue;
          }
          const double res = pt.P(2, 2);
          // Converged at round-off of the stress (the floor, 1e-15 mu, matters only at P = 0).
          const double scale = pt.P.cwiseAbs().maxCoeff() + mu_;
          if (std::abs(res) <= 1e-15 * scale) {
            converged = true;
            break;
          }
          if (res > 0.0) hi = std::min(hi, z); else lo = std::max(lo, z);
          double zn = z - res / A3(8, 8);
          if (!std::isfinite(zn) || !(zn > lo) || !(zn < hi)) zn = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * z;
          if (std::abs(zn - z) <= 4.0 * std::numeric_limits<double>::epsilon() * std::abs(z)) {
            converged = true;  // at round-off: the last evaluation stands
            break;
          }
          z = zn;
        }
        if (!converged) return false;
      }
      P = pt.P.topLeftCorner<2, 2>();
      if (A) {
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c)
              for (int d = 0; d < 2; ++d) {
                double v = A3(a * 3 + b, c * 3 + d);
                if (spec_.planar == PlanarMode::PlaneStress) v -= A3(a * 3 + b, 8) * A3(8, c * 3 + d) / A3(8, 8);
                (*A)(a * 2 + b, c * 2 + d) = v;
              }
      }
      if (sigma) *sigma = finite ? Mat3(pt.tau / pt.J) : pt.tau;
      if (trial) {
        trial[0] = pt.state[0];
        trial[1] = pt.state[1];
        trial[2] = pt.state[3];
        trial[3] = pt.state[5];
        trial[4] = pt.state[6];
        trial[5] = pt.state[7];
        if (spec_.planar == PlanarMode::PlaneStress) trial[6] = z;
      }
      return true;
    }
  }
}

void Material::initialState(double* s) const {
  for (int k = 0; k < stateSize_; ++k) s[k] = 0.0;
  if (!spec_.plastic.enabled) return;
  if (spec_.dim == 2 && spec_.planar == PlanarMode::PlaneStress) s[6] = 1.0;  // F33
  if (spec_.kind != MaterialKind::Hencky || spec_.dim == 1) return;
  if (spec_.dim == 2) {
    s[0] = s[2] = s[3] = 1.0;  // c = I
  } else {
    s[0] = s[3] = s[5] = 1.0;
  }
}

namespace {
int alphaIndex(int dim) { return dim == 1 ? 1 : dim == 2 ? 4 : 6; }
}  // namespace

double Material::equivalentPlasticStrain(const double* state) const {
  if (!spec_.plastic.enabled || !state) return 0.0;
  return state[alphaIndex(spec_.dim)];
}

bool Material::yielding(const double* state) const {
  if (!spec_.plastic.enabled || !state) return false;
  return state[alphaIndex(spec_.dim) + 1] != 0.0;
}

template <int D>
bool Material::stress(const MatD<D>& F, const double* committed, MatD<D>& P, double* trial) const {
  if (!spec_.plastic.enabled) return stress<D>(F, P);
  return plasticEval<D>(F, committed, P, nullptr, trial, nullptr);
}

template <int D>
bool Material::stressTangent(const MatD<D>& F, const double* committed, MatD<D>& P, TangentD<D>& A,
                             double* trial) const {
  if (!spec_.plastic.enabled) return stressTangent<D>(F, P, A);
  return plasticEval<D>(F, committed, P, &A, trial, nullptr);
}

template <int D>
bool Material::cauchy(const MatD<D>& F, const double* committed, Eigen::Matrix3d& sigma) const {
  if (!spec_.plastic.enabled) return cauchy<D>(F, sigma);
  MatD<D> P;
  return plasticEval<D>(F, committed, P, nullptr, nullptr, &sigma);
}

#define PERINOX_PLASTIC_INSTANTIATE(D)                                                                     \
  template bool Material::plasticEval<D>(const MatD<D>&, const double*, MatD<D>&, TangentD<D>*, double*,  \
                                         Eigen::Matrix3d*) const;                                          \
  template bool Material::stress<D>(const MatD<D>&, const double*, MatD<D>&, double*) const;              \
  template bool Material::stressTangent<D>(const MatD<D>&, const double*, MatD<D>&, TangentD<D>&,         \
                                           double*) const;                                                 \
  template bool Material::cauchy<D>(const MatD<D>&, const double*, Eigen::Matrix3d&) const;

PERINOX_PLASTIC_INSTANTIATE(1)
PERINOX_PLASTIC_INSTANTIATE(2)
PERINOX_PLASTIC_INSTANTIATE(3)

#undef PERINOX_PLASTIC_INSTANTIATE

}  // namespace perinox
