#pragma once
// The force-state effects. Each is one kernel; the model holds only the ones a scene enables.
#include "perinox/model/Model.hpp"

namespace perinox {

/// Correspondence force state T = P(F) K^-1 xi (seed 000 eq. 12, corrected) and its tangent
/// dT_j/du_k = (A : dF/du_k) h_j, with dF/du_k = e_c (x) g_k.
template <int D>
class CorrespondenceEffect final : public ForceEffect<D> {
 public:
  explicit CorrespondenceEffect(const Material& m) : material_(m) {}
  const char* name() const override { return "correspondence"; }
  void addForces(BondWork<D>& w, bool tangent) const override;

 private:
  const Material& material_;
};

/// Silling's stabilisation: T_z = (G C / w0_i) (Y - F xi), w0_i = sum_j V_j / V_i.
template <int D>
class StabilizationEffect final : public ForceEffect<D> {
 public:
  explicit StabilizationEffect(const StabilizationSpec& s) : spec_(s) {}
  const char* name() const override { return "stabilization"; }
  void addForces(BondWork<D>& w, bool tangent) const override;

 private:
  StabilizationSpec spec_;
};

}  // namespace perinox
