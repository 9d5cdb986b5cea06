#pragma once
// The one exception a model throws when it cannot be evaluated at a state (an inverted or
// non-finite deformation, a singular shape tensor, a return map that does not converge). Generic
// code (Newton, the steppers) catches it to cut a step back without knowing what the model is.
#include <stdexcept>
#include <string>

namespace perinox {

/// Thrown when a model cannot be evaluated at a configuration. The message names what failed
/// and where; index() is the entity it failed at (a particle's global id; -1: none).
class EvaluationError : public std::runtime_error {
 public:
  explicit EvaluationError(const std::string& what, long long index = -1) : std::runtime_error(what), index_(index) {}
  long long index() const { return index_; }
  long long particle() const { return index_; }  // the peridynamic model's name for index()

 private:
  long long index_;
};

}  // namespace perinox
