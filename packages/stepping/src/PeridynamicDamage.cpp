// perinox's damage effect as a DamagePolicy (PeridynamicDamage.hpp).
#include "perinox/stepping/PeridynamicDamage.hpp"

#include <sstream>
#include <stdexcept>

namespace perinox {

namespace {

DamagePolicy::Breaks breaks(const PeridynamicEvaluator::BreakReport& r) {
  DamagePolicy::Breaks b;
  b.brokenBonds = r.brokenBonds;
  b.detached = r.detached;
  b.fragmentParticles = r.fragmentParticles;
  return b;
}

}  // namespace

PeridynamicDamage::PeridynamicDamage(PeridynamicEvaluator& evaluator, const PeridynamicDamageOptions& o)
    : ev_(evaluator), stallTolerance_(o.stallBreakTolerance) {
  if (!ev_.problem().damage) throw std::invalid_argument("PeridynamicDamage: the evaluator's problem has no damage (ProblemSpec::damage is false)");
  if (o.maxBreakRounds < 0 || o.maxStallBreaks < 0 || !(o.stallBreakTolerance >= 0) ||
      !(o.reloadTolerance > 0 && o.reloadTolerance < 0.5))
    throw std::invalid_argument("PeridynamicDamage: the options need maxBreakRounds, maxStallBreaks >= 0, "
                                "stallBreakTolerance >= 0 and 0 < reloadTolerance < 0.5");
  maxBreakRounds = o.maxBreakRounds;
  breakOnStalls = o.breakOnStalls;
  maxStallBreaks = o.maxStallBreaks;
  reloadTolerance = o.reloadTolerance;
  breakAtSnapBackLimit = o.breakAtSnapBackLimit;
}

DamagePolicy::Breaks PeridynamicDamage::breakAfterStep(const Thyra::VectorBase<double>& x) {
  return breaks(ev_.breakBonds(x));
}

DamagePolicy::Breaks PeridynamicDamage::breakOnStall(const Thyra::VectorBase<double>& x, const std::string&) {
  const auto& ds = ev_.problem().damageSpec;
  double smax = 0;
  Breaks b = breaks(ev_.breakMostStretched(x, stallTolerance_ * (ds.sCr - ds.sMin), smax));
  b.maxStretch = smax;
  std::ostringstream s;
  s << "  stall at load factor " << ev_.loadFactor() << ": broke " << b.brokenBonds << " bond(s) at the largest stretch "
    << smax << " (softening band [" << ds.sMin << ", " << ds.sCr << ")), re-equilibrating";
  b.note = s.str();
  return b;
}

std::string PeridynamicDamage::nothingToBreak() const {
  return "no intact bond in the softening band to break ('Damage/On Stall')";
}

std::string PeridynamicDamage::stallLimitReached() const {
  return "'Damage/Max Stall Breaks' = " + std::to_string(maxStallBreaks) + " reached";
}

}  // namespace perinox
