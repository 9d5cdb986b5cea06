#pragma once
// Shared helpers for the material tests: specs, rotations, deformation cases and a
// central-difference tangent.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "perinox/material/Material.hpp"

namespace perinox::testutil {

constexpr double kPi = 3.14159265358979323846;
constexpr double kE = 200.0;  // arbitrary stress unit; all checks are relative to E or |A|
constexpr double kNu = 0.3;

inline MaterialSpec makeSpec(MaterialKind kind, int dim, PlanarMode planar, double E = kE, double nu = kNu) {
  MaterialSpec s;
  s.kind = kind;
  s.dim = dim;
  s.planar = planar;
  s.E = E;
  s.nu = nu;
  return s;
}

inline Eigen::Matrix2d rot2(double deg) {
  const double t = deg * kPi / 180.0;
  Eigen::Matrix2d R;
  R << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
  return R;
}

inline Eigen::Matrix3d rot3(double deg, Eigen::Vector3d axis) {
  return Eigen::AngleAxisd(deg * kPi / 180.0, axis.normalized()).toRotationMatrix();
}

template <int D>
struct FCase {
  std::string name;
  MatD<D> F;
};

/// Deformation gradients exercising distinct, nearly equal and exactly equal principal stretches.
template <int D>
std::vector<FCase<D>> deformationCases();

template <>
inline std::vector<FCase<1>> deformationCases<1>() {
  auto m = [](double f) { return (MatD<1>() << f).finished(); };
  return {{"near identity", m(1.0123)}, {"stretch 1.8", m(1.8)}, {"compression 0.6", m(0.6)},
          {"1.61", m(1.61)}, {"identity", m(1.0)}};
}

template <>
inline std::vector<FCase<2>> deformationCases<2>() {
  std::srand(7);  // deterministic "random" F near identity
  const Eigen::Matrix2d nearI = Eigen::Matrix2d::Identity() + 0.05 * Eigen::Matrix2d::Random();
  const double s = 1.3;
  return {
      {"random near identity", nearI},
      {"large: stretches 1.8, 0.6, rotated", rot2(30) * Eigen::Vector2d(1.8, 0.6).asDiagonal() * rot2(-50)},
      {"nearly equal: 1.3, 1.3(1+1e-7)", rot2(20) * Eigen::Vector2d(s, s * (1 + 1e-7)).asDiagonal() * rot2(-65)},
      {"nearly equal, unrotated", Eigen::Vector2d(s, s * (1 + 1e-7)).asDiagonal().toDenseMatrix()},
      {"equal: 1.61 I", 1.61 * Eigen::Matrix2d::Identity()},
      {"equal: R(37deg) * 1.2", 1.2 * rot2(37)},
      {"identity", Eigen::Matrix2d::Identity()},
  };
}

template <>
inline std::vector<FCase<3>> deformationCases<3>() {
  std::srand(11);
  const Eigen::Matrix3d nearI = Eigen::Matrix3d::Identity() + 0.05 * Eigen::Matrix3d::Random();
  const Eigen::Matrix3d R1 = rot3(30, {1, 2, 3}), R2 = rot3(-50, {-2, 1, 0.5});
  const double s = 1.3;
  auto diag = [](double a, double b, double c) { return Eigen::Vector3d(a, b, c).asDiagonal().toDenseMatrix(); };
  return {
      {"random near identity", nearI},
      {"large: stretches 1.8, 0.6, 1.1, rotated", R1 * diag(1.8, 0.6, 1.1) * R2},
      {"two nearly equal: 1.3, 1.3(1+1e-7), 0.9", R1 * diag(s, s * (1 + 1e-7), 0.9) * R2},
      {"three nearly equal", R1 * diag(s, s * (1 + 1e-7), s * (1 - 1e-7)) * R2},
      {"two equal: 1.2, 1.2, 0.8, rotated", R1 * diag(1.2, 1.2, 0.8) * R2},
      {"equal: 1.61 I", 1.61 * Eigen::Matrix3d::Identity()},
      {"equal: R(37deg) * 1.2", 1.2 * rot3(37, {0.3, -1, 2})},
      {"identity", Eigen::Matrix3d::Identity()},
  };
}

/// Central differences of stress(): column c*D+d = (P(F + h e_c e_d^T) - P(F - h ...)) / 2h,
/// from the committed state `committed` of a material with history (nullptr: the virgin state).
template <int D>
TangentD<D> fdTangent(const Material& m, const MatD<D>& F, double h, const double* committed = nullptr) {
  TangentD<D> A;
  for (int c = 0; c < D; ++c)
    for (int d = 0; d < D; ++d) {
      MatD<D> Fp = F, Fm = F, Pp, Pm;
      Fp(c, d) += h;
      Fm(c, d) -= h;
      EXPECT_TRUE(m.stress<D>(Fp, committed, Pp, nullptr));
      EXPECT_TRUE(m.stress<D>(Fm, committed, Pm, nullptr));
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) A(a * D + b, c * D + d) = (Pp(a, b) - Pm(a, b)) / (2 * h);
    }
  return A;
}

template <class M1, class M2>
double relMaxDiff(const M1& a, const M2& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

}  // namespace perinox::testutil
