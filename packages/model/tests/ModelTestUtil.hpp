#pragma once
// Helpers shared by the model's tests: a dense assembly sink and a small lattice.
#include <Eigen/Dense>

#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"

namespace perinox::testutil {

/// Assembles element contributions into a dense global residual and matrix (serial, all owned).
struct DenseSink : ElementSink {
  int D, n;
  Eigen::VectorXd r;
  Eigen::MatrixXd K;
  DenseSink(int dim, int np) : D(dim), n(np), r(Eigen::VectorXd::Zero(dim * np)), K(Eigen::MatrixXd::Zero(dim * np, dim * np)) {}
  void add(const int* p, int m, const double* re, const double* Ke) override {
    const int nd = m * D;
    for (int a = 0; a < m; ++a)
      for (int c = 0; c < D; ++c) {
        r[p[a] * D + c] += re[a * D + c];
        if (!Ke) continue;
        for (int b = 0; b < m; ++b)
          for (int e = 0; e < D; ++e) K(p[a] * D + c, p[b] * D + e) += Ke[(a * D + c) * nd + b * D + e];
      }
  }
};

inline Discretization smallLattice(int dim, double factor, int nx) {
  LatticeSpec s;
  s.dim = dim;
  s.counts = {nx, dim > 1 ? nx - 1 : 1, dim > 2 ? nx - 2 : 1};
  s.lower = Vec3::Zero();
  s.upper = Vec3(nx * 0.1, dim > 1 ? (nx - 1) * 0.1 : 1.0, dim > 2 ? (nx - 2) * 0.1 : 1.0);
  s.horizonFactor = factor;
  s.thickness = 0.05;
  return buildLattice(s);
}

}  // namespace perinox::testutil
