// Region selection: boxes, boundary layers, fictitious layers, nearest particle.
#include "perinox/core/Discretization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace perinox {

namespace {

bool inPopulation(const Discretization& d, int i, Population who) {
  switch (who) {
    case Population::Real: return d.fictitious[i] == 0;
    case Population::Fictitious: return d.fictitious[i] != 0;
    default: return true;
  }
}

void checkSide(const Discretization& d, Side s, const char* fn) {
  const int si = static_cast<int>(s);
  if (si < 0 || si >= 2 * d.dim)
    throw std::invalid_argument(std::string(fn) + ": side " + sideName(s) + " does not exist in " +
                                std::to_string(d.dim) + "D");
}

}  // namespace

std::vector<int> selectBox(const Discretization& d, const Vec3& lo, const Vec3& hi,
                           Population who) {
  // Closed box, widened by a tolerance relative to the spacing so that particles placed exactly
  // on a face (up to rounding) are included.
  const double tol = 1e-9 * d.dx;
  std::vector<int> out;
  for (int i = 0; i < d.size(); ++i) {
    if (!inPopulation(d, i, who)) continue;
    bool in = true;
    for (int a = 0; a < d.dim && in; ++a)
      in = d.X[i][a] >= lo[a] - tol && d.X[i][a] <= hi[a] + tol;
    if (in) out.push_back(i);
  }
  return out;
}

std::vector<int> selectSideLayer(const Discretization& d, Side s, double thickness) {
  checkSide(d, s, "selectSideLayer");
  const int si = static_cast<int>(s);
  const int axis = si / 2;
  const bool isMax = si % 2 == 1;
  std::vector<int> out;
  for (int i = 0; i < d.size(); ++i) {
    if (d.fictitious[i]) continue;
    // Distance from the side measured into the body (negative for a jittered particle that
    // crossed the box face, which is then still selected).
    const double inward = isMax ? d.boxUpper[axis] - d.X[i][axis] : d.X[i][axis] - d.boxLower[axis];
    if (inward < thickness) out.push_back(i);
  }
  return out;
}

std::vector<int> selectFictitiousSide(const Discretization& d, Side s) {
  checkSide(d, s, "selectFictitiousSide");
  const unsigned bit = 1u << static_cast<int>(s);
  std::vector<int> out;
  for (int i = 0; i < d.size(); ++i)
    if (d.fictitious[i] && (d.sideMask[i] & bit)) out.push_back(i);
  return out;
}

namespace {
double distanceTo(const Discretization& d, int i, const Vec3& p) {
  double dist2 = 0.0;
  for (int a = 0; a < d.dim; ++a) dist2 += (d.X[i][a] - p[a]) * (d.X[i][a] - p[a]);
  return std::sqrt(dist2);
}
}  // namespace

double nearestDistance(const Discretization& d, const Vec3& p, Population who) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < d.size(); ++i)
    if (inPopulation(d, i, who)) best = std::min(best, distanceTo(d, i, p));
  return best;
}

bool positionBefore(const Vec3& a, const Vec3& b, int dim) {
  for (int c = 0; c < dim; ++c)
    if (a[c] != b[c]) return a[c] < b[c];
  return false;
}

int selectNearest(const Discretization& d, const Vec3& p, Population who, double nearest) {
  if (nearest < 0) nearest = nearestDistance(d, p, who);
  if (!std::isfinite(nearest)) return -1;
  const double tie = nearest + 1e-9 * std::max(nearest, d.dx);
  int best = -1;
  for (int i = 0; i < d.size(); ++i) {
    if (!inPopulation(d, i, who) || distanceTo(d, i, p) > tie) continue;
    if (best < 0 || positionBefore(d.X[i], d.X[best], d.dim)) best = i;
  }
  return best;
}

}  // namespace perinox
