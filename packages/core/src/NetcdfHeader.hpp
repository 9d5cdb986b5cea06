#pragma once
#include <string>

namespace perinox {

/// Checks a classic netCDF file's header (CDF-1, -2, -5) against the file's length: every
/// declared count fits within the file, and so does every fixed-size variable. Throws
/// std::runtime_error with the reason ("is truncated, ...") otherwise. For files of untrusted
/// origin, before the netCDF library allocates what the header declares.
void checkClassicNetcdfHeader(const std::string& path);

}  // namespace perinox
