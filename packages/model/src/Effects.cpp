#include "Effects.hpp"

#include <sstream>

namespace perinox {

template <int D>
void CorrespondenceEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  using Mat = typename BondWork<D>::Mat;
  Mat P;
  TangentD<D> A;
  const bool ok = tangent ? material_.template stressTangent<D>(w.F, P, A)
                          : material_.template stress<D>(w.F, P);
  if (!ok) {
    std::ostringstream s;
    s << "deformation gradient is inverted or not finite (det F = " << w.F.determinant() << ")";
    throw EvaluationError(s.str(), w.i);
  }
  for (int j = 0; j < w.m; ++j) w.t[j].noalias() += P * w.h[j];
  if (!tangent) return;
  // M_j(a, c*D+d) = sum_b A(a*D+b, c*D+d) h_j,b ; block(j,k)(a,c) = sum_d M_j(a, c*D+d) g_k,d.
  Eigen::Matrix<double, D, D * D> M;
  for (int j = 0; j < w.m; ++j) {
    for (int a = 0; a < D; ++a)
      M.row(a) = w.h[j].transpose() * A.template block<D, D * D>(a * D, 0);
    for (int k = 0; k <= w.m; ++k) {
      const auto gk = w.g(k);
      Mat& B = w.dT(j, k);
      for (int c = 0; c < D; ++c)
        B.col(c).noalias() += M.template block<D, D>(0, c * D) * gk;
    }
  }
}

template <int D>
void StabilizationEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  double w0 = 0;
  for (int j = 0; j < w.m; ++j) w0 += w.Vj[j];
  w0 /= w.Vi;
  const double c = spec_.G * spec_.C / w0;
  for (int j = 0; j < w.m; ++j) w.t[j].noalias() += c * (w.Y[j] - w.F * w.xi[j]);
  if (!tangent) return;
  // dT_j/du_k = c [ (delta_{k,j} - delta_{k,i}) - g_k . xi_j ] I
  for (int j = 0; j < w.m; ++j) {
    for (int k = 0; k <= w.m; ++k) {
      double s = -w.g(k).dot(w.xi[j]);
      if (k == 0) s -= 1.0;
      if (k == j + 1) s += 1.0;
      w.dT(j, k).diagonal().array() += c * s;
    }
  }
}

template class CorrespondenceEffect<1>;
template class CorrespondenceEffect<2>;
template class CorrespondenceEffect<3>;
template class StabilizationEffect<1>;
template class StabilizationEffect<2>;
template class StabilizationEffect<3>;

}  // namespace perinox
