#pragma once
// The one place where a family's kinematics are formed, for every effect, the outputs and the
// damage criterion: the shape tensor K = sum_j V_j xi_j (x) xi_j, the deformation gradient
// F = (sum_j V_j Y_j (x) xi_j) K^-1 (and its directional derivative dF, with dY for Y), and the
// bond stretch s = (|Y| - |xi|) / |xi|. Templates over Eigen's fixed and dynamic sizes, so each
// caller keeps its matrix type (the arithmetic is the same term by term).
#include <cmath>

namespace perinox::kinematics {

/// K += V xi (x) xi.
template <class M, class V>
inline void addToShapeTensor(M& K, double Vj, const V& xi) {
  K.noalias() += Vj * xi * xi.transpose();
}

/// S += V a (x) xi: FK (a = Y) or its directional derivative dFK (a = dY).
template <class M, class V>
inline void addToDeformationSum(M& S, double Vj, const V& a, const V& xi) {
  S.noalias() += Vj * a * xi.transpose();
}

/// K += V xi (x) xi and FK += V Y (x) xi: one bond of the sums that give K and F = FK K^-1.
template <class M, class V>
inline void addBond(M& K, M& FK, double Vj, const V& xi, const V& Y) {
  addToShapeTensor(K, Vj, xi);
  addToDeformationSum(FK, Vj, Y, xi);
}

/// F = FK K^-1 (or dF = dFK K^-1 from the sums of V dY (x) xi).
template <class M>
inline M deformationGradient(const M& FK, const M& Kinv) {
  return FK * Kinv;
}

/// The bond stretch (|Y| - |xi|) / |xi| from the squared lengths |xi|^2 and |Y|^2.
inline double stretch(double xi2, double y2) { return (std::sqrt(y2) - std::sqrt(xi2)) / std::sqrt(xi2); }

}  // namespace perinox::kinematics
