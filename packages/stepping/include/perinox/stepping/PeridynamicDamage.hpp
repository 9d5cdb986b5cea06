#pragma once
// perinox's damage effect as the load stepper's DamagePolicy (seed 000, Fig. 8): after a
// converged step, bonds with stretch >= s_cr break (and particles left without an invertible
// shape tensor, or cut off from every support, are detached); optionally, a step that cannot be
// converged breaks the most stretched bonds in the softening band (a stall break). The stepper
// core (LoadStepper.cpp) knows nothing of this; a host application that runs perinox's evaluator
// with damage hands this policy to its LoadStepper.
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/stepping/LoadStepper.hpp"

namespace perinox {

struct PeridynamicDamageOptions {
  int maxBreakRounds = 50;           // re-equilibrations per load step
  bool breakOnStalls = false;        // 'Damage/On Stall' = Break Most Stretched
  int maxStallBreaks = 200;
  double stallBreakTolerance = 1e-6; // bonds within this fraction of (s_cr - s_min) of the largest break together
  double reloadTolerance = 0.01;     // a snap-back's limit load found to this fraction
  bool breakAtSnapBackLimit = false; // 'Damage/After Snap-Back' = Break Most Stretched (needs breakOnStalls)
};

class PeridynamicDamage final : public DamagePolicy {
 public:
  /// The evaluator's problem must have damage enabled (std::invalid_argument otherwise).
  PeridynamicDamage(PeridynamicEvaluator& evaluator, const PeridynamicDamageOptions& options);
  Breaks breakAfterStep(const Thyra::VectorBase<double>& x) override;
  Breaks breakOnStall(const Thyra::VectorBase<double>& x, const std::string& why) override;
  std::string nothingToBreak() const override;
  std::string stallLimitReached() const override;

 private:
  PeridynamicEvaluator& ev_;
  double stallTolerance_;
};

}  // namespace perinox
