#pragma once
// Result writers: VTK XML unstructured grids of particles (.vtu per rank + .pvtu index),
// and an output folder that is either complete or absent (files are staged, then renamed).
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace perinox {

/// A named point field: ncomp values per particle, interleaved (p0c0 p0c1 ... p1c0 ...).
struct PointField {
  std::string name;
  int ncomp = 1;
  std::vector<double> values;
};

/// Writes one VTK XML UnstructuredGrid file (ASCII, VTK_VERTEX cells) holding the given
/// points (always 3 coordinates; reference positions) and fields. ParaView opens it.
/// Throws std::runtime_error if the file cannot be written.
void writeVtu(const std::string& path, const std::vector<Eigen::Vector3d>& points,
              const std::vector<PointField>& fields);

/// Writes the .pvtu index naming the per-rank pieces (file names relative to the .pvtu),
/// declaring the same fields (names and component counts) as the pieces.
void writePvtu(const std::string& path, const std::vector<std::string>& pieceFiles,
               const std::vector<PointField>& fieldsLayout);

/// Writes text to path atomically: writes path + ".tmp" and renames it over path.
void writeFileAtomic(const std::string& path, const std::string& text);

}  // namespace perinox
