#include "perinox/model/Model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "Effects.hpp"
#include "Kinematics.hpp"

namespace perinox {

template <int D>
typename BondWork<D>::Vec BondWork<D>::g(int k) const {
  if (k == 0) return -gsum;
  return Vj[k - 1] * h[k - 1];
}

double micromodulusC(const MaterialSpec& m, double delta, double thickness) {
  const double pi = 3.14159265358979323846;
  switch (m.dim) {
    case 1:
      return 2.0 * m.E / (thickness * delta * delta * delta);
    case 2: {
      const double kp = m.planar == PlanarMode::PlaneStress ? m.E / (2.0 * (1.0 - m.nu))
                                                           : m.E / (2.0 * (1.0 - m.nu - 2.0 * m.nu * m.nu));
      return 12.0 * kp / (pi * thickness * std::pow(delta, 4));
    }
    default: {
      const double k = m.E / (3.0 * (1.0 - 2.0 * m.nu));
      return 18.0 * k / (pi * std::pow(delta, 5));
    }
  }
}

struct Model::Impl {
  virtual ~Impl() = default;
  virtual void evaluate(const Model& m, const std::vector<double>& u, ElementSink& sink,
                        bool tangent) const = 0;
  virtual std::vector<ParticleOutput> outputs(const Model& m, const std::vector<double>& u) const = 0;
  virtual void addCorrespondence(const std::vector<Material>& mats) = 0;
  virtual void addStabilization(const std::vector<StabilizationSpec>& perMaterial) = 0;
  virtual void setDamage(const Model* m) = 0;
  virtual void addControl(const ControlSpec& c) = 0;
  virtual void addStressPoints(const std::vector<Material>& m, unsigned seed) = 0;
  virtual std::vector<std::string> names() const = 0;
  virtual void applyTangent(const Model& m, const std::vector<double>& u, const std::vector<double>& v,
                            double* jv) const = 0;
  virtual void addDiagonal(const Model& m, const std::vector<double>& u, double* d) const = 0;
  virtual void prepare(const LocalParticles& p) = 0;
  virtual void invalidate() = 0;
  /// Writes the trial state at u over `state` (owned particles' blocks, as Model::state_).
  virtual void commit(const Model& m, const std::vector<double>& u, double* state) const = 0;
  Model::ProductForm form = Model::ProductForm::Auto;
};

namespace {

// The two per-bond loops of the gathered matrix-free product (ImplD::applyAffineGathered): sum
// the N-double records of a family's members, add one record to each member's. (Clones for AVX2
// and AVX-512 were no faster: the loads of the members' records, not the adds, take the time.)
template <int N>
void gatherRecords(const double* rec, const int* idx, int m, double* out) {
  double s[N] = {};
  for (int q = 0; q < m; ++q) {
    const double* r = rec + static_cast<std::size_t>(idx[q]) * N;
#pragma GCC unroll 16
    for (int c = 0; c < N; ++c) s[c] += r[c];
  }
  for (int c = 0; c < N; ++c) out[c] = s[c];
}
template <int N>
void scatterRecord(double* rec, const int* idx, int m, const double* add) {
  for (int q = 0; q < m; ++q) {
    double* r = rec + static_cast<std::size_t>(idx[q]) * N;
#pragma GCC unroll 16
    for (int c = 0; c < N; ++c) r[c] += add[c];
  }
}

template <int D>
struct ImplD final : Model::Impl {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  std::vector<std::unique_ptr<ForceEffect<D>>> effects;
  const Model* damage = nullptr;  // the model, once damage is enabled (its bondDamage gives each bond's law)

  void setDamage(const Model* m) override {
    damage = m;
    linValid_ = false;
  }
  void addControl(const ControlSpec& c) override { effects.push_back(std::make_unique<ControlEffect<D>>(c)); }
  void addStressPoints(const std::vector<Material>& m, unsigned seed) override {
    effects.push_back(std::make_unique<StressPointEffect<D>>(m, seed));
  }

  /// Bond softening applied to the summed force state of every effect:
  /// t_j <- T_s(s_j) t_j and dt_j/du_k <- T_s dt_j/du_k + t_j (x) T_s' ds_j/du_k, where
  /// ds_j/du_j = Y_j / (|Y_j| |xi_j|) = -ds_j/du_i.
  static void soften(const Model& model, BondWork<D>& w, bool tangent) {
    for (int j = 0; j < w.m; ++j) {
      const double ly = w.Y[j].norm(), lx = w.xi[j].norm();
      double Ts, dTs;
      bondSoftening(model.bondDamage(w.i, w.nbr[j]), (ly - lx) / lx, Ts, dTs);
      if (tangent) {
        w.forColumns(j, [&](int k) { w.dT(j, k) *= Ts; });
        if (dTs != 0.0 && ly > 0) {
          const Vec dsdu = w.Y[j] / (ly * lx);
          const Mat B = dTs * w.t[j] * dsdu.transpose();
          w.dT(j, j + 1) += B;
          w.dT(j, 0) -= B;
        }
      }
      w.t[j] *= Ts;
    }
  }

  /// The directional form of soften: dt_j <- T_s dt_j + T_s' (Y_j . dY_j / (|Y_j| |xi_j|)) t_j,
  /// then t_j <- T_s t_j.
  /// With soft, each bond's T_s and T_s' / (|Y_j| |xi_j|) (0 outside the band) are kept there
  /// (two doubles a bond) for the affine products that follow at this state.
  static void softenDirectional(const Model& model, BondWork<D>& w, double* soft) {
    for (int j = 0; j < w.m; ++j) {
      const double ly = w.Y[j].norm(), lx = w.xi[j].norm();
      double Ts, dTs;
      bondSoftening(model.bondDamage(w.i, w.nbr[j]), (ly - lx) / lx, Ts, dTs);
      const double gamma = dTs != 0.0 && ly > 0 ? dTs / (ly * lx) : 0.0;
      w.dt[j] *= Ts;
      if (gamma != 0.0) w.dt[j] += (gamma * w.Y[j].dot(w.dY[j])) * w.t[j];
      w.t[j] *= Ts;
      if (soft) {
        soft[2 * j] = Ts;
        soft[2 * j + 1] = gamma;
      }
    }
  }

  // The linearisation kept between matrix-free products: the state it belongs to and, per
  // effect, cacheSize() doubles per owned particle.
  mutable std::vector<double> linU_;
  mutable std::vector<std::vector<double>> linCache_;
  mutable std::vector<Mat> linKinv_;  // K^-1 per owned particle at that state (shape only: kept while the bonds are)
  mutable std::vector<Mat> linF_;     // with damage: F per owned particle at that state
  mutable std::vector<double> linSoft_;  // with damage: T_s and T_s' / (|Y| |xi|) per bond (softenDirectional)
  mutable bool linValid_ = false;
  void invalidate() override { linValid_ = false; }

  void applyTangent(const Model& model, const std::vector<double>& u, const std::vector<double>& v,
                    double* jv) const override {
    const LocalParticles& p = model.particles();
    const bool fresh = !(linValid_ && linU_ == u);
    if (fresh) {
      linValid_ = false;
      linU_ = u;
      linCache_.resize(effects.size());
      for (std::size_t e = 0; e < effects.size(); ++e)
        linCache_[e].resize(static_cast<std::size_t>(p.numOwned) * effects[e]->cacheSize());
    }
    const bool affine = std::all_of(effects.begin(), effects.end(), [](const auto& e) { return e->affineDirectional(); });
    if (fresh) {
      linKinv_.assign(p.numOwned, Mat::Zero());
      linF_.assign(damage && affine ? p.numOwned : 0, Mat::Zero());
      linSoft_.assign(damage && affine ? 2 * static_cast<std::size_t>(p.famOffset[p.numOwned]) : 0, 0.0);
    }
    // A repeated product, when every effect's dt is affine in the bond (dt_l = A xi_l + c dY_l
    // + k), needs per bond only xi, dY and two short passes (and, with damage, the kept
    // softening of each bond).
    if (!fresh && affine) {
      if (damage || !linGathered_)
        applyAffine(model, u, v, jv);
      else
        applyAffineGathered(model, v, jv);
      linValid_ = true;
      return;
    }
    if (fresh && affine && !damage) keepFamilySums(p);
    BondWork<D> w;
    w.cacheFresh = fresh;
    for (int i = 0; i < p.numOwned; ++i) {
      if (model.detached(i)) continue;
      kinematics(p, u, i, w);
      attachState(model, i, w);
      if (fresh) linKinv_[i] = w.Kinv;
      if (fresh && damage && affine) linF_[i] = w.F;
      w.dY.resize(w.m);
      w.dt.assign(w.m, Vec::Zero());
      w.dF.setZero();
      for (int l = 0; l < w.m; ++l) {
        const int j = w.nbr[l];
        for (int a = 0; a < D; ++a) w.dY[l][a] = v[j * D + a] - v[i * D + a];
        kinematics::addToDeformationSum(w.dF, w.Vj[l], w.dY[l], w.h[l]);  // dF = sum V dY (x) K^-1 xi
      }
      try {
        for (std::size_t e = 0; e < effects.size(); ++e) {
          const int cs = effects[e]->cacheSize();
          w.cache = cs > 0 ? linCache_[e].data() + static_cast<std::size_t>(i) * cs : nullptr;
          effects[e]->addDirectional(w);
        }
      } catch (const EvaluationError& e) {
        std::ostringstream msg;
        msg << e.what() << " at particle " << p.globalId[i] << " (X = " << p.X[i].head(D).transpose() << ")";
        throw EvaluationError(msg.str(), p.globalId[i]);
      }
      if (damage)
        softenDirectional(*damage, w, fresh && affine ? linSoft_.data() + 2 * static_cast<std::size_t>(p.famOffset[i]) : nullptr);
      for (int l = 0; l < w.m; ++l) {
        const double s = w.Vi * w.Vj[l];
        const int j = w.nbr[l];
        for (int a = 0; a < D; ++a) {
          jv[i * D + a] -= s * w.dt[l][a];
          jv[j * D + a] += s * w.dt[l][a];
        }
      }
    }
    linValid_ = true;  // (an evaluation error above leaves it invalid)
  }

  // Without damage, what the gathered product keeps at a state: per owned particle sum_l V_l
  // and sum_l V_l xi_l, and the origin its positions are taken from (the owned particles'
  // centroid, so that the sums of positions lose as few digits as they can).
  mutable std::vector<double> linVsum_;
  mutable std::vector<Vec> linGX_;
  mutable Vec linOrigin_ = Vec::Zero();
  // Its per-product scratch, per local particle (owned and ghosts): R1 = [V v (x) X, V v] and
  // R2 = [sum_i V_i A_i, sum_i V_i c_i, sum_i V_i b_i] (see applyAffineGathered).
  static constexpr int kR1 = D * D + D, kR2 = D * D + 1 + D;
  mutable std::vector<double> r1_, r2_;

  // Whether repeated products take the gathered form. Auto: in 3D on families of 16 bonds and
  // more (at 3.015 dx 1.5-1.8x faster than the per-bond form; at 1.015 dx, 6 bonds, 1.1-1.4x
  // slower; in 2D at 3.015 dx only 1.1-1.4x faster, for sums of positions that lose more digits
  // on the long bodies 2D runs allow; bench_kernels, docs/performance.md).
  mutable bool linGathered_ = false;
  void keepFamilySums(const LocalParticles& p) const {
    linGathered_ = form == Model::ProductForm::Gathered ||
                   (form == Model::ProductForm::Auto && D == 3 &&
                    p.famIndex.size() >= 16 * static_cast<std::size_t>(std::max(p.numOwned, 1)));
    if (!linGathered_) return;
    linVsum_.assign(p.numOwned, 0.0);
    linGX_.assign(p.numOwned, Vec::Zero());
    Vec o = Vec::Zero();
    for (int i = 0; i < p.numOwned; ++i) o += p.X[i].template head<D>();
    linOrigin_ = p.numOwned > 0 ? Vec(o / p.numOwned) : Vec::Zero();
    for (int i = 0; i < p.numOwned; ++i)
      for (auto q = p.famOffset[i]; q < p.famOffset[i + 1]; ++q) {
        const int j = p.famIndex[q];
        linVsum_[i] += p.volume[j];
        linGX_[i] += p.volume[j] * (p.X[j] - p.X[i]).template head<D>();
      }
  }

  /// The repeated affine product without damage, rewritten so that a bond costs two short
  /// passes over per-particle records instead of its own vector algebra. With x_j = X_j - origin:
  ///   dF_i K_i = S_i = sum_l V_l (v_j - v_i) (x) xi_l = sum_l R1_j[V v (x) x] - (sum_l V_l v_j) (x) x_i - v_i (x) g_i,
  /// g_i = sum_l V_l xi_l; particle i's own share of the product is
  ///   -V_i sum_l V_l (A xi_l + c dY_l + k) = -V_i (A g_i + c (sum_l V_l v_j - Vsum_i v_i) + Vsum_i k),
  /// and bond l's share to j, V_i V_l (A (x_j - x_i) + c (v_j - v_i) + k), is summed over the i
  /// whose family holds j as V_j (P_j x_j + q_j v_j + b_j) with P_j = sum_i V_i A_i, q_j = sum_i
  /// V_i c_i and b_j = sum_i V_i (k_i - A_i x_i - c_i v_i). Sums of positions of size L (from
  /// the centroid) stand where the per-bond form has bonds of size delta: the gathered form
  /// loses more digits as L / delta grows, most for a homogeneous stretch, whose product cancels
  /// inside the body (tested against the per-bond form and the assembled tangent).
  void applyAffineGathered(const Model& model, const std::vector<double>& v, double* jv) const {
    const LocalParticles& p = model.particles();
    const int n = p.size();
    r1_.resize(static_cast<std::size_t>(n) * kR1);
    r2_.assign(static_cast<std::size_t>(n) * kR2, 0.0);
    for (int j = 0; j < n; ++j) {
      double* r = r1_.data() + static_cast<std::size_t>(j) * kR1;
      const double Vj = p.volume[j];
      for (int a = 0; a < D; ++a) {
        const double va = Vj * v[j * D + a];
        for (int b = 0; b < D; ++b) r[a * D + b] = va * (p.X[j][b] - linOrigin_[b]);
        r[D * D + a] = va;
      }
    }
    BondWork<D> w;
    for (int i = 0; i < p.numOwned; ++i) {
      if (model.detached(i)) continue;
      const auto b0 = p.famOffset[i], b1 = p.famOffset[i + 1];
      std::array<double, kR1> sum{};
      gatherRecords<kR1>(r1_.data(), p.famIndex.data() + b0, static_cast<int>(b1 - b0), sum.data());
      Vec xi, vi, a;
      for (int c = 0; c < D; ++c) {
        xi[c] = p.X[i][c] - linOrigin_[c];
        vi[c] = v[i * D + c];
        a[c] = sum[D * D + c];
      }
      const Vec& g = linGX_[i];
      Mat S;
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) S(r, c) = sum[r * D + c] - a[r] * xi[c] - vi[r] * g[c];
      w.i = i;
      w.m = static_cast<int>(b1 - b0);
      w.nbr = p.famIndex.data() + b0;
      w.Vi = p.volume[i];
      w.Vsum = linVsum_[i];
      w.VdYsum = a - w.Vsum * vi;
      w.Kinv = linKinv_[i];
      w.dF.noalias() = S * w.Kinv;
      AffineDirectional<D> f;
      for (std::size_t e = 0; e < effects.size(); ++e) {
        const int cs = effects[e]->cacheSize();
        w.cache = cs > 0 ? linCache_[e].data() + static_cast<std::size_t>(i) * cs : nullptr;
        effects[e]->addAffineDirectional(w, f, nullptr);
      }
      const Vec own = f.A * g + f.c * w.VdYsum + w.Vsum * f.k;
      for (int c = 0; c < D; ++c) jv[i * D + c] -= w.Vi * own[c];
      std::array<double, kR2> rec;
      const Vec bi = f.k - f.A * xi - f.c * vi;
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) rec[r * D + c] = w.Vi * f.A(r, c);
      rec[D * D] = w.Vi * f.c;
      for (int c = 0; c < D; ++c) rec[D * D + 1 + c] = w.Vi * bi[c];
      scatterRecord<kR2>(r2_.data(), p.famIndex.data() + b0, static_cast<int>(b1 - b0), rec.data());
    }
    for (int j = 0; j < n; ++j) {
      const double* r = r2_.data() + static_cast<std::size_t>(j) * kR2;
      const double Vj = p.volume[j];
      for (int a = 0; a < D; ++a) {
        double s = r[D * D] * v[j * D + a] + r[D * D + 1 + a];
        for (int b = 0; b < D; ++b) s += r[a * D + b] * (p.X[j][b] - linOrigin_[b]);
        jv[j * D + a] += Vj * s;
      }
    }
  }

  /// A repeated product at the kept state whose effects are all affine in the bond: per
  /// particle, one pass for dF = (sum_l V_l dY_l (x) xi_l) K^-1 (K is symmetric) and the family's
  /// sums, the effects' A, c and k, and one pass for dt_l = A xi_l + c dY_l + k into jv. With
  /// damage each bond's dt is softened as softenDirectional does, from the kept T_s and
  /// gamma = T_s' / (|Y| |xi|): dt_l <- T_s dt_l + gamma (Y_l . dY_l) t_l, with the unsoftened
  /// t_l = A0 xi_l + c0 Y_l + k0 formed only for the bonds in the softening band (gamma != 0).
  void applyAffine(const Model& model, const std::vector<double>& u, const std::vector<double>& v, double* jv) const {
    const LocalParticles& p = model.particles();
    BondWork<D> w;
    for (int i = 0; i < p.numOwned; ++i) {
      if (model.detached(i)) continue;
      family(p, i, w);
      w.dY.resize(w.m);
      const Eigen::Vector3d& Xi = p.X[i];
      Vec vi, ui;
      for (int a = 0; a < D; ++a) {
        vi[a] = v[i * D + a];
        ui[a] = u[i * D + a];
      }
      // The sums live in locals (registers), the inner loops unrolled: this is the hot loop of
      // a matrix-free Krylov iteration.
      Mat S = Mat::Zero();
      Vec VdY = Vec::Zero(), VU = Vec::Zero();
      double Vsum = 0;
      for (int l = 0; l < w.m; ++l) {
        const int j = w.nbr[l];
        const double Vj = p.volume[j];
        const double* Xj = p.X[j].data();
        const double* vj = v.data() + static_cast<std::size_t>(j) * D;
        Vec xi, dY;
#pragma GCC unroll 3
        for (int a = 0; a < D; ++a) {
          xi[a] = Xj[a] - Xi[a];
          dY[a] = vj[a] - vi[a];
        }
        w.xi[l] = xi;
        w.dY[l] = dY;
        w.Vj[l] = Vj;
        Vsum += Vj;
#pragma GCC unroll 3
        for (int a = 0; a < D; ++a) {
          const double wa = Vj * dY[a];
          VdY[a] += wa;
#pragma GCC unroll 3
          for (int b = 0; b < D; ++b) S(a, b) += wa * xi[b];
        }
        if (damage)
          for (int a = 0; a < D; ++a) VU[a] += Vj * (u[j * D + a] - ui[a]);
      }
      w.Vsum = Vsum;
      w.VdYsum = VdY;
      w.VUsum = VU;
      w.Kinv = linKinv_[i];
      w.dF.noalias() = S * w.Kinv;
      if (damage) w.F = linF_[i];
      AffineDirectional<D> f, f0;
      for (std::size_t e = 0; e < effects.size(); ++e) {
        const int cs = effects[e]->cacheSize();
        w.cache = cs > 0 ? linCache_[e].data() + static_cast<std::size_t>(i) * cs : nullptr;
        effects[e]->addAffineDirectional(w, f, damage ? &f0 : nullptr);
      }
      const Mat A = f.A;
      const double c = f.c;
      const Vec k = f.k;
      const double* soft = damage ? linSoft_.data() + 2 * static_cast<std::size_t>(p.famOffset[i]) : nullptr;
      Vec ji = Vec::Zero();
      for (int l = 0; l < w.m; ++l) {
        const Vec xi = w.xi[l], dY = w.dY[l];
        const int j = w.nbr[l];
        Vec dt;
#pragma GCC unroll 3
        for (int a = 0; a < D; ++a) {
          double d = c * dY[a] + k[a];
#pragma GCC unroll 3
          for (int b = 0; b < D; ++b) d += A(a, b) * xi[b];
          dt[a] = d;
        }
        if (soft) {
          dt *= soft[2 * l];
          const double gamma = soft[2 * l + 1];
          if (gamma != 0.0) {
            Vec Y;
            for (int a = 0; a < D; ++a) Y[a] = xi[a] + u[j * D + a] - ui[a];
            const Vec t = f0.A * xi + f0.c * Y + f0.k;
            dt += (gamma * Y.dot(dY)) * t;
          }
        }
        const double s = w.Vi * w.Vj[l];
        double* jj = jv + static_cast<std::size_t>(j) * D;
#pragma GCC unroll 3
        for (int a = 0; a < D; ++a) {
          ji[a] -= s * dt[a];
          jj[a] += s * dt[a];
        }
      }
      for (int a = 0; a < D; ++a) jv[i * D + a] += ji[a];
    }
  }

  void addCorrespondence(const std::vector<Material>& mats) override {
    effects.push_back(std::make_unique<CorrespondenceEffect<D>>(mats));
  }
  void addStabilization(const std::vector<StabilizationSpec>& perMaterial) override {
    effects.push_back(std::make_unique<StabilizationEffect<D>>(perMaterial));
  }
  std::vector<std::string> names() const override {
    std::vector<std::string> n;
    for (const auto& e : effects) n.push_back(e->name());
    return n;
  }
  void prepare(const LocalParticles& p) override {
    for (auto& e : effects) e->prepare(p);
    linValid_ = false;
    order_ = tileOrder(p);
  }
  // The order evaluate() visits the owned particles in: tiles of about 8 horizons a side, row by
  // row, each tile's particles in id order. An element adds into the matrix rows of its whole
  // family, and every row is touched by each element that holds it; visiting elements tile by
  // tile keeps those rows in cache between touches (about 7 % of a Newton iteration on a 2D
  // block of 51 200 particles at delta = 3.015 dx, docs/performance.md).
  std::vector<int> order_;
  static std::vector<int> tileOrder(const LocalParticles& p) {
    std::vector<int> o(p.numOwned);
    std::iota(o.begin(), o.end(), 0);
    double reach = 0;  // the longest bond
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    for (int i = 0; i < p.numOwned; ++i) {
      lo = lo.cwiseMin(p.X[i]);
      for (auto q = p.famOffset[i]; q < p.famOffset[i + 1]; ++q) reach = std::max(reach, (p.X[p.famIndex[q]] - p.X[i]).squaredNorm());
    }
    if (!(reach > 0)) return o;
    const double edge = 8 * std::sqrt(reach);
    std::vector<std::array<long long, 4>> key(p.numOwned);
    for (int i = 0; i < p.numOwned; ++i) {
      const Eigen::Vector3d c = (p.X[i] - lo) / edge;
      key[i] = {static_cast<long long>(c[2]), static_cast<long long>(c[1]), static_cast<long long>(c[0]), i};
    }
    std::sort(key.begin(), key.end());
    for (int i = 0; i < p.numOwned; ++i) o[i] = static_cast<int>(key[i][3]);
    return o;
  }

  /// Particle i's family in w: id, size, members, volume; xi, h and V_j sized.
  static void family(const LocalParticles& p, int i, BondWork<D>& w) {
    const auto b = p.famOffset[i];
    w.i = i;
    w.m = static_cast<int>(p.famOffset[i + 1] - b);
    w.nbr = p.famIndex.data() + b;
    w.Vi = p.volume[i];
    w.xi.resize(w.m);
    w.h.resize(w.m);
    w.Vj.resize(w.m);
  }

  /// Fills the kinematics of particle i: bonds, K, K^-1, F, h_j.
  static void kinematics(const LocalParticles& p, const std::vector<double>& u, int i,
                         BondWork<D>& w) {
    family(p, i, w);
    w.Y.resize(w.m);
    w.t.assign(w.m, Vec::Zero());
    Vec ui;
    for (int a = 0; a < D; ++a) ui[a] = u[i * D + a];
    w.K.setZero();
    Mat FK = Mat::Zero();
    for (int l = 0; l < w.m; ++l) {
      const int j = w.nbr[l];
      for (int a = 0; a < D; ++a) {
        w.xi[l][a] = p.X[j][a] - p.X[i][a];
        w.Y[l][a] = w.xi[l][a] + u[j * D + a] - ui[a];
      }
      w.Vj[l] = p.volume[j];
      kinematics::addBond(w.K, FK, w.Vj[l], w.xi[l], w.Y[l]);
    }
    w.Kinv = w.K.inverse();
    w.F = kinematics::deformationGradient(FK, w.Kinv);
    w.gsum.setZero();
    for (int l = 0; l < w.m; ++l) {
      w.h[l] = w.Kinv * w.xi[l];
      w.gsum += w.Vj[l] * w.h[l];
    }
  }

  /// Points w at the committed state of owned particle i (nothing without history).
  static void attachState(const Model& model, int i, BondWork<D>& w) {
    w.state = model.committedState(i);
    w.stateStride = model.stateStride();
  }

  void commit(const Model& model, const std::vector<double>& u, double* state) const override {
    const LocalParticles& p = model.particles();
    const std::size_t block = static_cast<std::size_t>(model.stateDoublesPerParticle());
    BondWork<D> w;
    for (int i = 0; i < p.numOwned; ++i) {
      if (model.detached(i)) continue;
      kinematics(p, u, i, w);
      w.state = w.trial = state + i * block;  // the material reads the committed state before writing
      w.stateStride = model.stateStride();
      addForces(model, w, false);
    }
  }

  /// Every effect's force states of particle w.i (and their derivatives), softened by damage.
  void addForces(const Model& model, BondWork<D>& w, bool tangent) const {
    try {
      for (const auto& e : effects) e->addForces(w, tangent);
    } catch (const EvaluationError& e) {
      // Effects know local ids only; name the particle by its global id and position.
      const LocalParticles& p = model.particles();
      const long long g = p.globalId[w.i];
      std::ostringstream msg;
      msg << e.what() << " at particle " << g << " (X = " << p.X[w.i].head(D).transpose() << ")";
      throw EvaluationError(msg.str(), g);
    }
    if (damage) soften(*damage, w, tangent);
  }

  void evaluate(const Model& model, const std::vector<double>& u, ElementSink& sink,
                bool tangent) const override {
    const LocalParticles& p = model.particles();
    BondWork<D> w;
    std::vector<int> parts;
    std::vector<double> r, K;
    for (int ii = 0; ii < p.numOwned; ++ii) {
      const int i = order_.size() == static_cast<std::size_t>(p.numOwned) ? order_[ii] : ii;
      if (model.detached(i)) continue;
      kinematics(p, u, i, w);
      attachState(model, i, w);
      const int m = w.m;
      if (tangent) w.tan.assign(static_cast<std::size_t>(m) * (m + 1), Mat::Zero());
      addForces(model, w, tangent);

      const int n = m + 1;
      parts.resize(n);
      parts[0] = i;
      for (int l = 0; l < m; ++l) parts[l + 1] = w.nbr[l];
      r.assign(static_cast<std::size_t>(n) * D, 0.0);
      for (int l = 0; l < m; ++l) {
        const double s = w.Vi * w.Vj[l];
        for (int a = 0; a < D; ++a) {
          r[a] -= s * w.t[l][a];
          r[(l + 1) * D + a] += s * w.t[l][a];
        }
      }
      if (tangent) {
        const int nd = n * D;
        K.assign(static_cast<std::size_t>(nd) * nd, 0.0);
        for (int l = 0; l < m; ++l) {
          const double s = w.Vi * w.Vj[l];
          for (int k = 0; k < n; ++k) {
            const Mat& B = w.dT(l, k);
            for (int a = 0; a < D; ++a)
              for (int c = 0; c < D; ++c) {
                const double v = s * B(a, c);
                K[static_cast<std::size_t>(a) * nd + k * D + c] -= v;
                K[static_cast<std::size_t>((l + 1) * D + a) * nd + k * D + c] += v;
              }
          }
        }
      }
      sink.add(parts.data(), n, r.data(), tangent ? K.data() : nullptr);
    }
  }

  /// The element tangents' diagonal blocks, as evaluate() would form them (same effects, same
  /// softening), each dT(l, k) only for k = i and k = member l: K_ii = -sum_l s_l dT(l, 0),
  /// K_jj = s_l dT(l, l + 1) for member j = nbr[l], s_l = V_i V_l.
  void addDiagonal(const Model& model, const std::vector<double>& u, double* d) const override {
    const LocalParticles& p = model.particles();
    BondWork<D> w;
    w.diagonalOnly = true;
    for (int i = 0; i < p.numOwned; ++i) {  // into a vector: no tile order needed
      if (model.detached(i)) continue;
      kinematics(p, u, i, w);
      attachState(model, i, w);
      w.tan.assign(static_cast<std::size_t>(2 * w.m), Mat::Zero());
      addForces(model, w, true);
      for (int l = 0; l < w.m; ++l) {
        const double s = w.Vi * w.Vj[l];
        const Mat& Bi = w.dT(l, 0);
        const Mat& Bj = w.dT(l, l + 1);
        for (int a = 0; a < D; ++a) {
          d[i * D + a] -= s * Bi(a, a);
          d[w.nbr[l] * D + a] += s * Bj(a, a);
        }
      }
    }
  }

  /// Per particle: F and Cauchy stress. With stress points (seed 001), the particle's values are
  /// the averages over its stress points, each weighted by the volume of the bonds it owns
  /// (sum of V_j): F_p = (sum_{j in p} Y_j (x) xi_j V_j) K_p^-1 and sigma_p = sigma(F_p). On a
  /// uniform nearest-neighbour lattice the weights are equal (D bonds each). A particle with one
  /// stress point (defective family) reports that one. The stress carries the particle's modulus
  /// scale (the Cauchy stress of both materials is linear in it).
  std::vector<ParticleOutput> outputs(const Model& model, const std::vector<double>& u) const override {
    const LocalParticles& p = model.particles();
    std::vector<ParticleOutput> out(p.numOwned);
    const StressPointEffect<D>* sp = nullptr;
    for (const auto& e : effects)
      if (const auto* q = dynamic_cast<const StressPointEffect<D>*>(e.get())) sp = q;
    BondWork<D> w;
    std::vector<int> grp;
    for (int i = 0; i < p.numOwned; ++i) {
      if (model.detached(i)) {
        out[i].cauchy.setZero();
        continue;
      }
      kinematics(p, u, i, w);
      attachState(model, i, w);
      const double scale = p.modulusScale.empty() ? 1.0 : p.modulusScale[i];
      Mat F = w.F;
      Eigen::Matrix3d s;
      // An output state is a converged one, where every F is valid; should one not be, write
      // zero stress and flag it rather than a NaN.
      const int ng = sp ? sp->groups(w, grp) : 1;
      double eqps = 0.0;
      bool yielded = false;
      if (ng > 1) {
        Mat Fsum = Mat::Zero();
        Eigen::Matrix3d ssum = Eigen::Matrix3d::Zero();
        double vsum = 0;
        bool valid = true;
        for (int g = 0; g < ng; ++g) {
          Mat K = Mat::Zero(), FK = Mat::Zero();
          double v = 0;
          for (int l = 0; l < w.m; ++l) {
            if (grp[l] != g) continue;
            kinematics::addBond(K, FK, w.Vj[l], w.xi[l], w.Y[l]);
            v += w.Vj[l];
          }
          const Mat Fp = kinematics::deformationGradient<Mat>(FK, K.inverse());
          Eigen::Matrix3d sp3;
          const double* st = w.pointState(g);
          const bool ok = model.material(i).template cauchy<D>(Fp, st, sp3);
          valid = valid && ok;
          Fsum += v * Fp;
          if (ok) ssum += v * sp3;
          eqps += v * model.material(i).equivalentPlasticStrain(st);
          yielded = yielded || model.material(i).yielding(st);
          vsum += v;
        }
        F = Fsum / vsum;
        eqps /= vsum;
        out[i].valid = valid;
        s = valid ? Eigen::Matrix3d(ssum / vsum) : Eigen::Matrix3d::Zero();
      } else {
        out[i].valid = model.material(i).template cauchy<D>(F, w.state, s);
        if (!out[i].valid) s.setZero();
        eqps = model.material(i).equivalentPlasticStrain(w.state);
        yielded = model.material(i).yielding(w.state);
      }
      out[i].eqps = eqps;
      out[i].yielded = yielded;
      out[i].F.setIdentity();
      out[i].F.template topLeftCorner<D, D>() = F;
      out[i].cauchy = scale * s;
    }
    return out;
  }
};

/// Refuses two particles at one position (a repeated line of a particle file, a duplicated mesh
/// element): each would carry the whole volume there, so the body would be counted twice. Closer
/// than 1e-9 of the family's longest bond counts as one position.
void checkCoincident(const LocalParticles& p) {
  for (int i = 0; i < p.numOwned; ++i) {
    double longest = 0;
    for (auto q = p.famOffset[i]; q < p.famOffset[i + 1]; ++q)
      longest = std::max(longest, (p.X[p.famIndex[q]] - p.X[i]).norm());
    for (auto q = p.famOffset[i]; q < p.famOffset[i + 1]; ++q) {
      const int j = p.famIndex[q];
      if ((p.X[j] - p.X[i]).norm() > 1e-9 * longest) continue;
      std::ostringstream s;
      s.precision(10);
      s << "particles " << std::min(p.globalId[i], p.globalId[j]) << " and " << std::max(p.globalId[i], p.globalId[j])
        << " coincide (both at X = " << p.X[i].head(p.dim).transpose() << "); remove one of them";
      throw std::invalid_argument(s.str());
    }
  }
}

}  // namespace

Model::Model(const MaterialSpec& material, LocalParticles particles)
    : Model(std::vector<MaterialSpec>{material}, std::move(particles)) {}

Model::Model(const std::vector<MaterialSpec>& materials, LocalParticles particles) : particles_(std::move(particles)) {
  if (materials.empty()) throw std::invalid_argument("the model needs at least one material");
  materials_.reserve(materials.size());
  for (const MaterialSpec& m : materials) {
    if (m.dim != particles_.dim) throw std::invalid_argument("material dimension differs from the discretisation's");
    materials_.emplace_back(m);
  }
  if (!particles_.material.empty()) {
    if (particles_.material.size() != particles_.X.size())
      throw std::invalid_argument("LocalParticles::material needs one entry per local particle");
    for (int k : particles_.material)
      if (k < 0 || k >= static_cast<int>(materials_.size()))
        throw std::invalid_argument("LocalParticles::material names material " + std::to_string(k) + ", which the table does not have");
  }
  switch (particles_.dim) {
    case 1: impl_ = std::make_unique<ImplD<1>>(); break;
    case 2: impl_ = std::make_unique<ImplD<2>>(); break;
    case 3: impl_ = std::make_unique<ImplD<3>>(); break;
    default: throw std::invalid_argument("model dimension must be 1, 2 or 3");
  }
  checkCoincident(particles_);
  checkShapeTensors();
  initHistory();
  familyVolume0_.assign(particles_.numOwned, 0.0);
  for (int i = 0; i < particles_.numOwned; ++i)
    for (auto q = particles_.famOffset[i]; q < particles_.famOffset[i + 1]; ++q)
      familyVolume0_[i] += particles_.volume[particles_.famIndex[q]];
}

void Model::enableControl(const ControlSpec& c) {
  impl_->addControl(c);
  impl_->prepare(particles_);
}

void Model::enableStressPoints(unsigned seed) {
  impl_->addStressPoints(materials_, seed);
  impl_->prepare(particles_);
  statePoints_ = 2;  // a complete nearest-neighbour family has two stress points
  initHistory();
}

void Model::initHistory() {
  stateStride_ = 0;
  for (const Material& m : materials_) stateStride_ = std::max(stateStride_, m.stateSize());
  state_.assign(static_cast<std::size_t>(particles_.numOwned) * stateStride_ * statePoints_, 0.0);
  for (int i = 0; i < particles_.numOwned && stateStride_ > 0; ++i)
    for (int q = 0; q < statePoints_; ++q)
      material(i).initialState(state_.data() + (static_cast<std::size_t>(i) * statePoints_ + q) * stateStride_);
}

void Model::commitState(const std::vector<double>& u) {
  if (stateStride_ == 0) return;
  std::vector<double> next = state_;  // all or nothing: an evaluation error commits nothing
  impl_->commit(*this, u, next.data());
  state_.swap(next);
  impl_->invalidate();  // the kept linearisation of the matrix-free product belongs to the old state
}

void Model::setCommittedStates(const std::vector<double>& s) {
  if (s.size() != state_.size())
    throw std::invalid_argument("Model::setCommittedStates: " + std::to_string(s.size()) + " values for a state of " +
                                std::to_string(state_.size()));
  state_ = s;
  impl_->invalidate();
}

void Model::enableDamage(const DamageSpec& d) {
  if (!(d.sMin > 0 && d.sCr > d.sMin && d.beta > 0))
    throw std::invalid_argument("damage needs 0 < s_min < s_cr and beta > 0");
  if (d.criticalPlasticStrain > 0 && stateStride_ == 0)
    throw std::invalid_argument("the damage law breaks bonds by plastic strain (Critical Plastic Strain), but no material is plastic");
  damage_ = d;
  damageLaws_.clear();
  impl_->setDamage(this);
}

void Model::enableDamage(const std::vector<DamageSpec>& perMaterial) {
  if (perMaterial.size() != materials_.size())
    throw std::invalid_argument("enableDamage needs one damage law per material (" + std::to_string(materials_.size()) + ")");
  for (const DamageSpec& d : perMaterial)
    if (!(d.sMin > 0 && d.sCr > d.sMin && d.beta > 0))
      throw std::invalid_argument("damage needs 0 < s_min < s_cr and beta > 0");
  for (const DamageSpec& d : perMaterial)
    if (d.criticalPlasticStrain > 0 && stateStride_ == 0)
      throw std::invalid_argument("a damage law breaks bonds by plastic strain (Critical Plastic Strain), but no material is plastic");
  damage_ = perMaterial.front();
  damageLaws_ = perMaterial;
  impl_->setDamage(this);
}

const DamageSpec& Model::bondDamage(int i, int j) const {
  if (damageLaws_.empty() || particles_.material.empty()) return *damage_;
  const int a = particles_.material[i], b = particles_.material[j];
  if (a == b) return damageLaws_[a];
  const DamageSpec &da = damageLaws_[a], &db = damageLaws_[b];
  // The end with the smaller critical stretch decides (ties: the lower index): symmetric in (i, j).
  return da.sCr < db.sCr || (da.sCr == db.sCr && a < b) ? da : db;
}

long long Model::breakBonds(const std::vector<double>& u, const std::vector<double>& eqps) {
  if (!damage_) return 0;
  if (eqps.size() != static_cast<std::size_t>(particles_.size()))
    throw std::invalid_argument("Model::breakBonds: " + std::to_string(eqps.size()) + " plastic strains for " +
                                std::to_string(particles_.size()) + " local particles");
  return breakBondsWhere(u, &eqps);
}

long long Model::breakBondsWhere(const std::vector<double>& u, const std::vector<double>* eqps) {
  long long broken = 0;
  removeBondsIf([&](int i, int j) {
    const DamageSpec& d = bondDamage(i, j);
    const bool brk = (d.stretchCriterion && bondStretch(u, i, j) >= d.sCr) ||
                     (eqps && d.criticalPlasticStrain > 0 && 0.5 * ((*eqps)[i] + (*eqps)[j]) >= d.criticalPlasticStrain);
    // Count each bond once over all ranks: at the end with the lower global id.
    broken += brk && particles_.globalId[i] < particles_.globalId[j];
    return !brk;
  });
  return broken;
}

bool Model::ductileCriterion() const {
  if (!damage_) return false;
  if (damage_->criticalPlasticStrain > 0) return true;
  for (const DamageSpec& d : damageLaws_)
    if (d.criticalPlasticStrain > 0) return true;
  return false;
}

std::vector<double> Model::trialPlasticStrain(const std::vector<double>& u) const {
  std::vector<double> out(particles_.numOwned, 0.0);
  if (stateStride_ == 0) return out;
  std::vector<double> trial = state_;
  impl_->commit(*this, u, trial.data());
  for (int i = 0; i < particles_.numOwned; ++i)
    for (int q = 0; q < statePoints_; ++q)
      out[i] = std::max(out[i], material(i).equivalentPlasticStrain(
                                    trial.data() + (static_cast<std::size_t>(i) * statePoints_ + q) * stateStride_));
  return out;
}

long long Model::breakBonds(const std::vector<double>& u) {
  if (!damage_) return 0;
  if ((damageLaws_.empty() || particles_.material.empty()) && damage_->stretchCriterion) return breakBondsAbove(u, damage_->sCr);
  return breakBondsWhere(u, nullptr);
}

double Model::bondStretch(const std::vector<double>& u, int i, int j) const {
  // Both ends of a bond evaluate this with the same operands in the same order, so they agree
  // bit for bit (ranks decide breaking without talking).
  const int D = particles_.dim;
  double ly2 = 0, lx2 = 0;
  for (int a = 0; a < D; ++a) {
    const double xi = particles_.X[j][a] - particles_.X[i][a];
    const double y = xi + (u[j * D + a] - u[i * D + a]);
    ly2 += y * y;
    lx2 += xi * xi;
  }
  return kinematics::stretch(lx2, ly2);
}

double Model::maxIntactStretch(const std::vector<double>& u) const {
  double best = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < particles_.numOwned; ++i) {
    if (detached(i)) continue;
    for (auto q = particles_.famOffset[i]; q < particles_.famOffset[i + 1]; ++q) {
      best = std::max(best, bondStretch(u, i, particles_.famIndex[q]));
    }
  }
  return best;
}

long long Model::breakBondsAbove(const std::vector<double>& u, double sBreak) {
  if (!damage_) return 0;
  long long broken = 0;
  removeBondsIf([&](int i, int j) {
    const bool brk = bondStretch(u, i, j) >= sBreak;
    // Count each bond once over all ranks: at the end with the lower global id.
    broken += brk && particles_.globalId[i] < particles_.globalId[j];
    return !brk;
  });
  return broken;
}

void Model::familiesChanged() { impl_->invalidate(); }

void Model::isolate(const std::vector<long long>& globalIds) {
  if (globalIds.empty()) return;
  std::vector<char> gone(particles_.size(), 0);
  for (int l = 0; l < particles_.size(); ++l)
    if (std::binary_search(globalIds.begin(), globalIds.end(), particles_.globalId[l])) gone[l] = 1;
  removeBondsIf([&](int i, int j) { return !gone[i] && !gone[j]; });
}

std::vector<long long> Model::singularParticles() const {
  std::vector<long long> out;
  for (int i = 0; i < particles_.numOwned; ++i)
    if (!detached(i) && !shapeTensorInvertible(i)) out.push_back(particles_.globalId[i]);
  return out;
}

void Model::markDetached(const std::vector<long long>& globalIds) {
  if (detached_.empty()) detached_.assign(particles_.numOwned, 0);
  for (int i = 0; i < particles_.numOwned; ++i)
    if (std::binary_search(globalIds.begin(), globalIds.end(), particles_.globalId[i])) detached_[i] = 1;
}

std::vector<double> Model::unitStressForceScale() const {
  const int D = particles_.dim;
  std::vector<double> out(particles_.size(), 0.0);
  for (int i = 0; i < particles_.numOwned; ++i) {
    if (detached(i)) continue;
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(D, D);
    for (auto q = particles_.famOffset[i]; q < particles_.famOffset[i + 1]; ++q) {
      const int j = particles_.famIndex[q];
      const Eigen::VectorXd xi = (particles_.X[j] - particles_.X[i]).head(D);
      kinematics::addToShapeTensor(K, particles_.volume[j], xi);
    }
    if (particles_.famOffset[i + 1] == particles_.famOffset[i]) continue;
    const Eigen::MatrixXd Kinv = K.inverse();
    for (auto q = particles_.famOffset[i]; q < particles_.famOffset[i + 1]; ++q) {
      const int j = particles_.famIndex[q];
      const Eigen::VectorXd xi = (particles_.X[j] - particles_.X[i]).head(D);
      const double f = particles_.volume[i] * particles_.volume[j] * (Kinv * xi).norm();
      out[i] += f;
      out[j] += f;
    }
  }
  return out;
}

std::vector<double> Model::damageIndex() const {
  std::vector<double> phi(particles_.numOwned, 0.0);
  for (int i = 0; i < particles_.numOwned; ++i) {
    double v = 0;
    for (auto q = particles_.famOffset[i]; q < particles_.famOffset[i + 1]; ++q) v += particles_.volume[particles_.famIndex[q]];
    phi[i] = familyVolume0_[i] > 0 ? 1.0 - v / familyVolume0_[i] : 0.0;
  }
  return phi;
}

Model::~Model() = default;

void Model::enableCorrespondence() { impl_->addCorrespondence(materials_); impl_->prepare(particles_); }
void Model::enableStabilization(const StabilizationSpec& s) { enableStabilization(std::vector<StabilizationSpec>(materials_.size(), s)); }
void Model::enableStabilization(const std::vector<StabilizationSpec>& perMaterial) {
  if (perMaterial.size() != materials_.size())
    throw std::invalid_argument("enableStabilization needs one entry per material (" + std::to_string(materials_.size()) + ")");
  for (const StabilizationSpec& s : perMaterial)
    if (!(s.C >= 0) || !std::isfinite(s.C))
      throw std::invalid_argument("the stabilisation needs a micromodulus C >= 0 (micromodulusC, or ProblemSpec::stabilizationSpec)");
  impl_->addStabilization(perMaterial);
  impl_->prepare(particles_);
}
std::vector<std::string> Model::effectNames() const { return impl_->names(); }

void Model::evaluate(const std::vector<double>& u, ElementSink& sink, bool wantTangent) const {
  impl_->evaluate(*this, u, sink, wantTangent);
}

void Model::applyTangent(const std::vector<double>& u, const std::vector<double>& v, double* jv) const {
  impl_->applyTangent(*this, u, v, jv);
}

void Model::setProductForm(ProductForm f) {
  impl_->form = f;
  impl_->invalidate();
}

void Model::addJacobianDiagonal(const std::vector<double>& u, double* d) const { impl_->addDiagonal(*this, u, d); }

std::vector<ParticleOutput> Model::outputs(const std::vector<double>& u) const {
  return impl_->outputs(*this, u);
}

bool Model::shapeTensorInvertible(int i) const {
  // A shape tensor must be invertible: the family has to span the space. Measure conditioning
  // relative to the family's own scale so the check is unit-free.
  const int D = particles_.dim;
  Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
  double scale = 0;
  for (auto p = particles_.famOffset[i]; p < particles_.famOffset[i + 1]; ++p) {
    const int j = particles_.famIndex[p];
    Eigen::Vector3d xi = particles_.X[j] - particles_.X[i];
    kinematics::addToShapeTensor(K, particles_.volume[j], xi);
    scale += particles_.volume[j] * xi.squaredNorm();
  }
  if (!(scale > 0)) return false;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K.topLeftCorner(D, D));
  return es.eigenvalues().minCoeff() > 1e-10 * scale;
}

void Model::checkShapeTensors() const {
  for (int i = 0; i < particles_.numOwned; ++i) {
    if (detached(i)) continue;
    if (!shapeTensorInvertible(i)) {
      std::ostringstream s;
      s << "particle " << particles_.globalId[i] << " has a singular shape tensor (family of "
        << (particles_.famOffset[i + 1] - particles_.famOffset[i])
        << " bonds does not span the space); it must be detached or the horizon enlarged";
      throw EvaluationError(s.str(), particles_.globalId[i]);
    }
  }
}

template struct BondWork<1>;
template struct BondWork<2>;
template struct BondWork<3>;

}  // namespace perinox
