#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "perinox/io/Output.hpp"

namespace perinox {

void writeFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error("cannot write " + tmp);
    out << text;
    if (!out) throw std::runtime_error("error while writing " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot rename " + tmp + " to " + path);
}

void writeVtu(const std::string& path, const std::vector<Eigen::Vector3d>& points,
              const std::vector<PointField>& fields) {
  std::ostringstream o;
  o << std::setprecision(12);
  const std::size_t n = points.size();
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n << "\">\n";
  o << "<PointData>\n";
  for (const auto& f : fields) {
    if (f.values.size() != n * static_cast<std::size_t>(f.ncomp))
      throw std::runtime_error("field " + f.name + " has the wrong size for " + path);
    o << "<DataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\"" << f.ncomp
      << "\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < f.values.size(); ++i) o << f.values[i] << ((i + 1) % f.ncomp ? ' ' : '\n');
    o << "</DataArray>\n";
  }
  o << "</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& p : points) o << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
  o << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) o << i << '\n';
  o << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) o << i + 1 << '\n';
  o << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) o << "1\n";  // VTK_VERTEX
  o << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  writeFileAtomic(path, o.str());
}

void writePvtu(const std::string& path, const std::vector<std::string>& pieceFiles,
               const std::vector<PointField>& fieldsLayout) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "<PUnstructuredGrid GhostLevel=\"0\">\n<PPointData>\n";
  for (const auto& f : fieldsLayout)
    o << "<PDataArray type=\"Float64\" Name=\"" << f.name << "\" NumberOfComponents=\"" << f.ncomp << "\"/>\n";
  o << "</PPointData>\n<PPoints>\n<PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n</PPoints>\n";
  for (const auto& p : pieceFiles) o << "<Piece Source=\"" << p << "\"/>\n";
  o << "</PUnstructuredGrid>\n</VTKFile>\n";
  writeFileAtomic(path, o.str());
}

}  // namespace perinox
