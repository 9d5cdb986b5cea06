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
  if (!scale_.empty()) {
    P *= scale_[w.i];
    if (tangent) A *= scale_[w.i];
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

template <int D>
void ControlEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  using Vec = typename BondWork<D>::Vec;
  // u_j - u_i = Y_j - xi_j
  if (spec_.kind == ControlSpec::Kind::Springs) {
    for (int j = 0; j < w.m; ++j) w.t[j].noalias() += spec_.C * (w.Y[j] - w.xi[j]);
    if (!tangent) return;
    for (int j = 0; j < w.m; ++j) {
      w.dT(j, j + 1).diagonal().array() += spec_.C;
      w.dT(j, 0).diagonal().array() -= spec_.C;
    }
    return;
  }
  Vec avg = Vec::Zero();
  double vsum = 0;
  for (int l = 0; l < w.m; ++l) {
    avg += w.Vj[l] * (w.Y[l] - w.xi[l]);
    vsum += w.Vj[l];
  }
  for (int j = 0; j < w.m; ++j) w.t[j].noalias() += spec_.C * avg;
  if (!tangent) return;
  for (int j = 0; j < w.m; ++j) {
    for (int l = 0; l < w.m; ++l) w.dT(j, l + 1).diagonal().array() += spec_.C * w.Vj[l];
    w.dT(j, 0).diagonal().array() -= spec_.C * vsum;
  }
}

template <int D>
void StressPointEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  using Vec = typename BondWork<D>::Vec;
  using Mat = typename BondWork<D>::Mat;
  if (D != 1) throw std::logic_error("stress points are implemented in 1D only");
  // Two groups: bonds to the left (xi < 0) and to the right (xi > 0). A particle with bonds on
  // one side only (a boundary) has one stress point holding them all.
  for (int side = 0; side < 2; ++side) {
    Mat K = Mat::Zero(), FK = Mat::Zero();
    int count = 0;
    for (int l = 0; l < w.m; ++l) {
      if ((w.xi[l][0] > 0) != (side == 1)) continue;
      K.noalias() += w.Vj[l] * w.xi[l] * w.xi[l].transpose();
      FK.noalias() += w.Vj[l] * w.Y[l] * w.xi[l].transpose();
      ++count;
    }
    if (count == 0) continue;
    const Mat Kinv = K.inverse();
    const Mat F = FK * Kinv;
    Mat P;
    TangentD<D> A;
    const bool ok = tangent ? material_.template stressTangent<D>(F, P, A) : material_.template stress<D>(F, P);
    if (!ok) throw EvaluationError("stress-point deformation gradient is inverted or not finite", w.i);
    const double sc = w.i < static_cast<int>(scale_.size()) ? scale_[w.i] : 1.0;
    P *= sc;
    A *= sc;
    Vec gsum = Vec::Zero();
    for (int l = 0; l < w.m; ++l) {
      if ((w.xi[l][0] > 0) != (side == 1)) continue;
      const Vec h = Kinv * w.xi[l];
      w.t[l].noalias() += P * h;
      gsum += w.Vj[l] * h;
    }
    if (!tangent) continue;
    for (int j = 0; j < w.m; ++j) {
      if ((w.xi[j][0] > 0) != (side == 1)) continue;
      const Vec hj = Kinv * w.xi[j];
      Eigen::Matrix<double, D, D * D> M;
      for (int a = 0; a < D; ++a) M.row(a) = hj.transpose() * A.template block<D, D * D>(a * D, 0);
      for (int k = 0; k <= w.m; ++k) {
        Vec gk;
        if (k == 0) {
          gk = -gsum;
        } else {
          if ((w.xi[k - 1][0] > 0) != (side == 1)) continue;
          gk = w.Vj[k - 1] * (Kinv * w.xi[k - 1]);
        }
        for (int c = 0; c < D; ++c) w.dT(j, k).col(c).noalias() += M.template block<D, D>(0, c * D) * gk;
      }
    }
  }
}

template class ControlEffect<1>;
template class ControlEffect<2>;
template class ControlEffect<3>;
template class StressPointEffect<1>;
template class StressPointEffect<2>;
template class StressPointEffect<3>;
template class CorrespondenceEffect<1>;
template class CorrespondenceEffect<2>;
template class CorrespondenceEffect<3>;
template class StabilizationEffect<1>;
template class StabilizationEffect<2>;
template class StabilizationEffect<3>;

}  // namespace perinox
