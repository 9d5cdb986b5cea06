// Names of the bounding-box sides ("xmin", ..., "zmax") used in input files and reports.
#include "perinox/core/Discretization.hpp"

#include <cctype>

namespace perinox {

namespace {
constexpr const char* kSideNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
}  // namespace

const char* sideName(Side s) {
  const int i = static_cast<int>(s);
  return (i >= 0 && i < 6) ? kSideNames[i] : "unknown";
}

bool parseSide(const std::string& name, Side& out) {
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (int i = 0; i < 6; ++i) {
    if (lower == kSideNames[i]) {
      out = static_cast<Side>(i);
      return true;
    }
  }
  return false;  // `out` untouched
}

}  // namespace perinox
