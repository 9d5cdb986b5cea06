#pragma once
// The force-state effects. Each is one kernel; the model holds only the ones a scene enables.
#include <stdexcept>

#include "perinox/model/Model.hpp"

namespace perinox {

/// Correspondence force state T = P(F) K^-1 xi (seed 000 eq. 12, corrected) and its tangent
/// dT_j/du_k = (A : dF/du_k) h_j, with dF/du_k = e_c (x) g_k.
template <int D>
class CorrespondenceEffect final : public ForceEffect<D> {
 public:
  explicit CorrespondenceEffect(const std::vector<Material>& m) : materials_(m) {}
  void prepare(const LocalParticles& p) override {
    scale_ = p.modulusScale;
    index_ = p.material;
  }
  const char* name() const override { return "correspondence"; }
  void addForces(BondWork<D>& w, bool tangent) const override;
  void addDirectional(BondWork<D>& w) const override;
  int cacheSize() const override { return D * D + D * D * D * D; }  // P and A = dP/dF
  bool affineDirectional() const override { return true; }
  void addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt, AffineDirectional<D>* t) const override;

 private:
  const Material& material(int i) const { return index_.empty() ? materials_.front() : materials_[index_[i]]; }
  const std::vector<Material>& materials_;
  std::vector<double> scale_;
  std::vector<int> index_;
};

/// Springs (C1) or average displacement state (C2) supplementary forces.
template <int D>
class ControlEffect final : public ForceEffect<D> {
 public:
  explicit ControlEffect(const ControlSpec& c) : spec_(c) {}
  const char* name() const override {
    return spec_.kind == ControlSpec::Kind::Springs ? "springs control" : "average displacement state control";
  }
  void addForces(BondWork<D>& w, bool tangent) const override;
  void addDirectional(BondWork<D>& w) const override;
  bool affineDirectional() const override { return true; }
  void addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt, AffineDirectional<D>* t) const override;

 private:
  ControlSpec spec_;
};

/// Stress-point correspondence (seed 001, section 3): each particle's family is split among
/// stress points; K_p, F_p and P_p are computed per stress point from its bonds, and a bond's
/// force state is P_p K_p^-1 xi with p the stress point owning it. Nearest-neighbour families:
/// a particle with its complete family (2 D bonds along the axes) has two stress points, the
/// first owning the bond towards -x and, for each further axis a, the bond towards -a or +a as
/// the particle's arrangement bit b_a says (1D: left/right; 2D: two arrangements; 3D: four).
/// The bits come from a hash of the global particle id, so they do not depend on the partition.
/// Any other family (boundaries) has one stress point holding all bonds.
template <int D>
class StressPointEffect final : public ForceEffect<D> {
 public:
  StressPointEffect(const std::vector<Material>& m, unsigned seed) : materials_(m), seed_(seed) {}
  const char* name() const override { return "stress-point correspondence"; }
  void prepare(const LocalParticles& p) override {
    scale_ = p.modulusScale;
    index_ = p.material;
    globalId_ = p.globalId;
  }
  void addForces(BondWork<D>& w, bool tangent) const override;
  void addDirectional(BondWork<D>& w) const override;
  /// Stress point (0 or 1) of each bond of w, or all 0 for a defective family; returns the count.
  int groups(const BondWork<D>& w, std::vector<int>& g) const;

 private:
  const Material& material(int i) const { return index_.empty() ? materials_.front() : materials_[index_[i]]; }
  const std::vector<Material>& materials_;
  unsigned seed_;
  std::vector<double> scale_;
  std::vector<int> index_;
  std::vector<long long> globalId_;
};

/// Silling's stabilisation: T_z = (G C / w0_i) (Y - F xi), w0_i = sum_j V_j / V_i, with G and C
/// of particle i's material (one entry per material of the model's table).
template <int D>
class StabilizationEffect final : public ForceEffect<D> {
 public:
  explicit StabilizationEffect(std::vector<StabilizationSpec> s) : specs_(std::move(s)) {}
  void prepare(const LocalParticles& p) override;
  const char* name() const override { return "stabilization"; }
  void addForces(BondWork<D>& w, bool tangent) const override;
  void addDirectional(BondWork<D>& w) const override;
  bool affineDirectional() const override { return true; }
  void addAffineDirectional(const BondWork<D>& w, AffineDirectional<D>& dt, AffineDirectional<D>* t) const override;

 private:
  const StabilizationSpec& spec(int i) const { return index_.empty() ? specs_.front() : specs_[index_[i]]; }
  /// G C of owned particle i (its Silling G: G, or G delta S_i / (3 V_i) in Peridigm's form).
  double GC(int i) const {
    const StabilizationSpec& s = spec(i);
    return s.G * s.C * (peridigmFactor_.empty() ? 1.0 : peridigmFactor_[i]);
  }
  std::vector<StabilizationSpec> specs_;
  std::vector<int> index_;
  std::vector<double> peridigmFactor_;  // per owned particle: delta S_i / (3 V_i) (1 in Silling's form); empty if none
};

}  // namespace perinox
