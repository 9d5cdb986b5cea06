#pragma once
// Results as one Exodus II file (Output/Format = Exodus or Both; docs/exodus.md): the particles
// as sphere elements, one element block per particle block id (the block structure of the mesh
// or particle file), attributes radius and volume (the sphere convention perinox and Peridigm
// read back); named node sets (the scene's regions); nodal variables and global variables per
// time step. Written by one process (rank 0, after gathering), or one file per rank of its
// particles; no Trilinos or MPI type here.
#include <Eigen/Dense>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace perinox {

/// True when perinox was built with the Exodus II library.
bool exodusOutputAvailable();

class ExodusWriter {
 public:
  /// Creates (or replaces) the file at path and writes the reference configuration: positions X
  /// (all particles, in id order: Exodus node p+1 and element of particle p), volumes, block ids,
  /// node sets (name -> sorted particle ids), the names of the nodal and global variables.
  /// dim is the scene's dimension (2D spheres get radius sqrt(V / (pi thickness))).
  /// A file of some of the particles (one rank's, of a run written one file per rank) gives
  /// their global ids in `ids` (X's order; node sets then hold indices into X): the node and
  /// element number maps hold ids + 1. Empty ids: X is every particle, in id order.
  /// Throws std::runtime_error naming the file when it cannot be written.
  ExodusWriter(const std::string& path, int dim, double thickness, const std::vector<Eigen::Vector3d>& X,
               const std::vector<double>& volume, const std::vector<int>& block,
               const std::map<std::string, std::vector<int>>& nodeSets, const std::vector<std::string>& nodalNames,
               const std::vector<std::string>& globalNames, const std::vector<long long>& ids = {});
  ~ExodusWriter();
  ExodusWriter(const ExodusWriter&) = delete;
  ExodusWriter& operator=(const ExodusWriter&) = delete;

  /// Appends a time step: its time value, each nodal variable's values for every particle
  /// (nodal[v][p]) and the global variables, then flushes the file.
  void writeStep(double time, const std::vector<std::vector<double>>& nodal, const std::vector<double>& globals);
  int steps() const { return steps_; }
  /// Closes the file (also done by the destructor); throws if closing fails.
  void close();

 private:
  std::string path_;
  int exo_ = -1;
  int steps_ = 0;
  std::size_t particles_ = 0, nodalVars_ = 0, globalVars_ = 0;
};

}  // namespace perinox
