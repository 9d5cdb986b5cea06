#include "Effects.hpp"
#include "Kinematics.hpp"

#include <sstream>

namespace perinox {

namespace {

/// P(F) (and A = dP/dF when tangent), times a modulus scale; throws for an inverted F.
/// committed: the point's committed state (nullptr without history); trial: where to write the
/// trial state (nullptr: nowhere).
template <int D>
void piola(const Material& m, const MatD<D>& F, const double* committed, double* trial, double scale, bool tangent,
           int particle, MatD<D>& P, TangentD<D>& A) {
  const bool ok = tangent ? m.template stressTangent<D>(F, committed, P, A, trial)
                          : m.template stress<D>(F, committed, P, trial);
  if (!ok) {
    std::ostringstream s;
    s << "deformation gradient is inverted or not finite (det F = " << F.determinant() << ")";
    throw EvaluationError(s.str(), particle);
  }
  if (scale != 1.0) {
    P *= scale;
    if (tangent) A *= scale;
  }
}

/// The correspondence force states of the bonds l with in(l) (one shape tensor K, one F):
/// t_l += P h_l, and, with A, dT_j/du_k += (A : e_c (x) g_k) h_j for k = i and every member,
/// where h_l = K^-1 xi_l, g_0 = -gsum = -sum V_l h_l and g_{1+l} = V_l h_l.
template <int D, class In>
void addPiolaForceStates(BondWork<D>& w, const MatD<D>& P, const TangentD<D>* A,
                         const std::vector<typename BondWork<D>::Vec>& h,
                         const typename BondWork<D>::Vec& gsum, In in) {
  for (int l = 0; l < w.m; ++l)
    if (in(l)) w.t[l].noalias() += P * h[l];
  if (!A) return;
  // M_j(a, c*D+d) = sum_b A(a*D+b, c*D+d) h_j,b ; block(j,k)(a,c) = sum_d M_j(a, c*D+d) g_k,d.
  Eigen::Matrix<double, D, D * D> M;
  for (int j = 0; j < w.m; ++j) {
    if (!in(j)) continue;
    for (int a = 0; a < D; ++a) M.row(a) = h[j].transpose() * A->template block<D, D * D>(a * D, 0);
    w.forColumns(j, [&](int k) {
      if (k > 0 && !in(k - 1)) return;
      const typename BondWork<D>::Vec gk = k == 0 ? (-gsum).eval() : (w.Vj[k - 1] * h[k - 1]).eval();
      for (int c = 0; c < D; ++c) w.dT(j, k).col(c).noalias() += M.template block<D, D>(0, c * D) * gk;
    });
  }
}

/// dP = A : dF, with A and the flattening row-major: dP(a,b) = sum_cd A(a*D+b, c*D+d) dF(c,d).
template <int D>
MatD<D> contract(const TangentD<D>& A, const MatD<D>& dF) {
  Eigen::Matrix<double, D * D, 1> f;
  for (int c = 0; c < D; ++c)
    for (int d = 0; d < D; ++d) f[c * D + d] = dF(c, d);
  const Eigen::Matrix<double, D * D, 1> p = A * f;
  MatD<D> dP;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) dP(a, b) = p[a * D + b];
  return dP;
}

}  // namespace

template <int D>
void CorrespondenceEffect<D>::addDirectional(BondWork<D>& w) const {
  MatD<D> P;
  TangentD<D> A;
  if (w.cache && !w.cacheFresh) {  // the state of the previous product: P(F) and A(F) kept
    P = Eigen::Map<const MatD<D>>(w.cache);
    A = Eigen::Map<const TangentD<D>>(w.cache + D * D);
  } else {
    piola<D>(material(w.i), w.F, w.state, nullptr, scale_.empty() ? 1.0 : scale_[w.i], true, w.i, P, A);
    if (w.cache) {
      Eigen::Map<MatD<D>>(w.cache) = P;
      Eigen::Map<TangentD<D>>(w.cache + D * D) = A;
    }
  }
  const MatD<D> dP = contract<D>(A, w.dF);
  for (int l = 0; l < w.m; ++l) {
    w.t[l].noalias() += P * w.h[l];
    w.dt[l].noalias() += dP * w.h[l];
  }
}

template <int D>
void StabilizationEffect<D>::addDirectional(BondWork<D>& w) const {
  double w0 = 0;
  for (int j = 0; j < w.m; ++j) w0 += w.Vj[j];
  const double c = GC(w.i) * w.Vi / w0;
  for (int j = 0; j < w.m; ++j) {
    w.t[j].noalias() += c * (w.Y[j] - w.F * w.xi[j]);
    w.dt[j].noalias() += c * (w.dY[j] - w.dF * w.xi[j]);
  }
}

// dt_l = dP K^-1 xi_l with dP = A(F) : dF; t_l = P K^-1 xi_l; P and A(F) kept in the cache.
template <int D>
void CorrespondenceEffect<D>::addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt,
                                                   AffineDirectional<D>* t) const {
  dt.A.noalias() += contract<D>(Eigen::Map<const TangentD<D>>(w.cache + D * D), w.dF) * w.Kinv;
  if (t) t->A.noalias() += Eigen::Map<const MatD<D>>(w.cache) * w.Kinv;
}

// dt_l = c (dY_l - dF xi_l), t_l = c (Y_l - F xi_l), c = G C V_i / sum V_j.
template <int D>
void StabilizationEffect<D>::addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt,
                                                  AffineDirectional<D>* t) const {
  const double c = GC(w.i) * w.Vi / w.Vsum;
  dt.A.noalias() -= c * w.dF;
  dt.c += c;
  if (t) {
    t->A.noalias() -= c * w.F;
    t->c += c;
  }
}

// Springs: dt_l = C dY_l, t_l = C (Y_l - xi_l); average displacement state: dt_l = C sum_j V_j
// dY_j, t_l = C sum_j V_j (Y_j - xi_j).
template <int D>
void ControlEffect<D>::addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt,
                                            AffineDirectional<D>* t) const {
  if (spec_.kind == ControlSpec::Kind::Springs) {
    dt.c += spec_.C;
    if (t) {
      t->A.diagonal().array() -= spec_.C;
      t->c += spec_.C;
    }
  } else {
    dt.k.noalias() += spec_.C * w.VdYsum;
    if (t) t->k.noalias() += spec_.C * w.VUsum;
  }
}

template <int D>
void ControlEffect<D>::addDirectional(BondWork<D>& w) const {
  using Vec = typename BondWork<D>::Vec;
  if (spec_.kind == ControlSpec::Kind::Springs) {
    for (int j = 0; j < w.m; ++j) {
      w.t[j].noalias() += spec_.C * (w.Y[j] - w.xi[j]);
      w.dt[j].noalias() += spec_.C * w.dY[j];
    }
    return;
  }
  Vec avg = Vec::Zero(), davg = Vec::Zero();
  for (int l = 0; l < w.m; ++l) {
    avg += w.Vj[l] * (w.Y[l] - w.xi[l]);
    davg += w.Vj[l] * w.dY[l];
  }
  for (int j = 0; j < w.m; ++j) {
    w.t[j].noalias() += spec_.C * avg;
    w.dt[j].noalias() += spec_.C * davg;
  }
}

template <int D>
void StressPointEffect<D>::addDirectional(BondWork<D>& w) const {
  using Mat = typename BondWork<D>::Mat;
  std::vector<int> grp;
  const int ng = groups(w, grp);
  const double sc = w.i < static_cast<int>(scale_.size()) ? scale_[w.i] : 1.0;
  for (int p = 0; p < ng; ++p) {
    Mat K = Mat::Zero(), FK = Mat::Zero(), dFK = Mat::Zero();
    for (int l = 0; l < w.m; ++l) {
      if (grp[l] != p) continue;
      kinematics::addBond(K, FK, w.Vj[l], w.xi[l], w.Y[l]);
      kinematics::addToDeformationSum(dFK, w.Vj[l], w.dY[l], w.xi[l]);
    }
    const Mat Kinv = K.inverse();
    Mat P;
    TangentD<D> A;
    piola<D>(material(w.i), kinematics::deformationGradient(FK, Kinv), w.pointState(p), nullptr, sc, true, w.i, P, A);
    const Mat dP = contract<D>(A, kinematics::deformationGradient(dFK, Kinv));
    for (int l = 0; l < w.m; ++l) {
      if (grp[l] != p) continue;
      const auto h = (Kinv * w.xi[l]).eval();
      w.t[l].noalias() += P * h;
      w.dt[l].noalias() += dP * h;
    }
  }
}

template <int D>
void CorrespondenceEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  MatD<D> P;
  TangentD<D> A;
  piola<D>(material(w.i), w.F, w.state, w.trial, scale_.empty() ? 1.0 : scale_[w.i], tangent, w.i, P, A);
  addPiolaForceStates<D>(w, P, tangent ? &A : nullptr, w.h, w.gsum, [](int) { return true; });
}

template <int D>
void StabilizationEffect<D>::prepare(const LocalParticles& p) {
  index_ = p.material;
  peridigmFactor_.clear();
  bool peridigm = false;
  for (const StabilizationSpec& s : specs_) peridigm = peridigm || s.form == StabilizationSpec::Form::PeridigmHourglass;
  if (!peridigm) return;
  peridigmFactor_.assign(p.numOwned, 1.0);
  for (int i = 0; i < p.numOwned; ++i) {
    const StabilizationSpec& s = spec(i);
    if (s.form != StabilizationSpec::Form::PeridigmHourglass) continue;
    double S = 0;
    for (auto q = p.famOffset[i]; q < p.famOffset[i + 1]; ++q) {
      const int j = p.famIndex[q];
      S += p.volume[j] / (p.X[j] - p.X[i]).norm();
    }
    peridigmFactor_[i] = s.horizon * S / (3.0 * p.volume[i]);
  }
}

template <int D>
void StabilizationEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  double w0 = 0;
  for (int j = 0; j < w.m; ++j) w0 += w.Vj[j];
  w0 /= w.Vi;
  const double c = GC(w.i) / w0;
  for (int j = 0; j < w.m; ++j) w.t[j].noalias() += c * (w.Y[j] - w.F * w.xi[j]);
  if (!tangent) return;
  // dT_j/du_k = c [ (delta_{k,j} - delta_{k,i}) - g_k . xi_j ] I
  for (int j = 0; j < w.m; ++j) {
    w.forColumns(j, [&](int k) {
      double s = -w.g(k).dot(w.xi[j]);
      if (k == 0) s -= 1.0;
      if (k == j + 1) s += 1.0;
      w.dT(j, k).diagonal().array() += c * s;
    });
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
  for (int j = 0; j < w.m; ++j)
    w.forColumns(j, [&](int k) {
      if (k > 0) w.dT(j, k).diagonal().array() += spec_.C * w.Vj[k - 1];
      else w.dT(j, 0).diagonal().array() -= spec_.C * vsum;
    });
}

template <int D>
int StressPointEffect<D>::groups(const BondWork<D>& w, std::vector<int>& g) const {
  g.assign(w.m, 0);
  if (w.m != 2 * D) return 1;
  // The arrangement bits of this particle, from a hash of its global id and the seed.
  unsigned long long h = static_cast<unsigned long long>(globalId_[w.i]) * 0x9E3779B97F4A7C15ull ^ (seed_ * 0xBF58476D1CE4E5B9ull);
  h ^= h >> 31;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 29;
  int seen = 0;
  for (int l = 0; l < w.m; ++l) {
    int axis = -1;
    for (int a = 0; a < D; ++a)
      if (std::abs(w.xi[l][a]) > 0.5 * w.xi[l].norm()) axis = a;
    if (axis < 0) return g.assign(w.m, 0), 1;
    const bool positive = w.xi[l][axis] > 0;
    const bool bit = axis > 0 && ((h >> axis) & 1ull);
    g[l] = positive != bit ? 1 : 0;
    seen |= 1 << (2 * axis + positive);
  }
  if (seen != (1 << (2 * D)) - 1) return g.assign(w.m, 0), 1;  // not one bond per direction
  return 2;
}

template <int D>
void StressPointEffect<D>::addForces(BondWork<D>& w, bool tangent) const {
  using Vec = typename BondWork<D>::Vec;
  using Mat = typename BondWork<D>::Mat;
  std::vector<int> grp;
  const int ng = groups(w, grp);
  const double sc = w.i < static_cast<int>(scale_.size()) ? scale_[w.i] : 1.0;
  std::vector<Vec> h(w.m);
  for (int p = 0; p < ng; ++p) {
    const auto in = [&](int l) { return grp[l] == p; };
    Mat K = Mat::Zero(), FK = Mat::Zero();
    for (int l = 0; l < w.m; ++l) {
      if (!in(l)) continue;
      kinematics::addBond(K, FK, w.Vj[l], w.xi[l], w.Y[l]);
    }
    const Mat Kinv = K.inverse();
    Vec gsum = Vec::Zero();
    for (int l = 0; l < w.m; ++l)
      if (in(l)) {
        h[l] = Kinv * w.xi[l];
        gsum += w.Vj[l] * h[l];
      }
    Mat P;
    TangentD<D> A;
    piola<D>(material(w.i), kinematics::deformationGradient(FK, Kinv), w.pointState(p), w.pointTrial(p), sc, tangent, w.i, P, A);
    addPiolaForceStates<D>(w, P, tangent ? &A : nullptr, h, gsum, in);
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
