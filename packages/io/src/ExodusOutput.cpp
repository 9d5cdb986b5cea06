// Exodus II results (docs/exodus.md), through the Exodus 6.02 C API: ex_create, ex_put_init,
// sphere element blocks, node sets, nodal and global variables per time step.
#include "perinox/io/ExodusOutput.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#ifdef PERINOX_HAVE_EXODUS
#include <exodusII.h>
#endif

namespace perinox {

bool exodusOutputAvailable() {
#ifdef PERINOX_HAVE_EXODUS
  return true;
#else
  return false;
#endif
}

#ifndef PERINOX_HAVE_EXODUS

ExodusWriter::ExodusWriter(const std::string& path, int, double, const std::vector<Eigen::Vector3d>&,
                           const std::vector<double>&, const std::vector<int>&,
                           const std::map<std::string, std::vector<int>>&, const std::vector<std::string>&,
                           const std::vector<std::string>&, const std::vector<long long>&)
    : path_(path) {
  throw std::runtime_error(path + ": this perinox was built without Exodus II and cannot write Exodus files");
}
ExodusWriter::~ExodusWriter() = default;
void ExodusWriter::writeStep(double, const std::vector<std::vector<double>>&, const std::vector<double>&) {}
void ExodusWriter::close() {}

#else

namespace {

constexpr int kNameLength = 80;  // names beyond Exodus' default 32 characters (region and probe names)

void check(int rc, const std::string& path, const char* what) {
  if (rc < 0) throw std::runtime_error("cannot write the Exodus file '" + path + "' (" + what + " failed)");
}

/// Exodus takes names as char* arrays.
struct Names {
  std::vector<std::string> text;
  std::vector<char*> ptr;
  explicit Names(const std::vector<std::string>& v) : text(v) {
    for (auto& s : text) {
      if (s.size() > static_cast<std::size_t>(kNameLength)) s.resize(kNameLength);
      ptr.push_back(s.data());
    }
  }
};

}  // namespace

ExodusWriter::ExodusWriter(const std::string& path, int dim, double thickness, const std::vector<Eigen::Vector3d>& X,
                           const std::vector<double>& volume, const std::vector<int>& block,
                           const std::map<std::string, std::vector<int>>& nodeSets,
                           const std::vector<std::string>& nodalNames, const std::vector<std::string>& globalNames,
                           const std::vector<long long>& ids)
    : path_(path), particles_(X.size()), nodalVars_(nodalNames.size()), globalVars_(globalNames.size()) {
  ex_opts(0);  // errors come back as return codes, turned into this writer's sentence
  int cpu = sizeof(double), io = sizeof(double);
  exo_ = ex_create(path.c_str(), EX_CLOBBER, &cpu, &io);
  if (exo_ < 0) throw std::runtime_error("cannot create the Exodus file '" + path + "'");
  try {
    ex_set_max_name_length(exo_, kNameLength);
    const int n = static_cast<int>(particles_);
    std::vector<int> blockIds(block);
    std::sort(blockIds.begin(), blockIds.end());
    blockIds.erase(std::unique(blockIds.begin(), blockIds.end()), blockIds.end());
    const int spatial = dim < 2 ? 2 : dim;  // 1D bars are drawn on the x axis of a 2D file
    check(ex_put_init(exo_, "perinox results", spatial, n, n, static_cast<int>(blockIds.size()),
                      static_cast<int>(nodeSets.size()), 0),
          path, "ex_put_init");
    std::vector<double> x(n), y(n), z(n);
    for (int p = 0; p < n; ++p) {
      x[p] = X[p][0];
      y[p] = X[p][1];
      z[p] = X[p][2];
    }
    check(ex_put_coord(exo_, x.data(), y.data(), z.data()), path, "ex_put_coord");
    if (!ids.empty() && ids.size() != particles_) throw std::logic_error("ExodusWriter: ids and positions differ in size");
    // Node p + 1 is particle p of X, whose id is ids[p] (or p): the node map holds the ids + 1.
    auto idOf = [&](int p) { return ids.empty() ? p + 1 : static_cast<int>(ids[p] + 1); };
    if (!ids.empty() && n > 0) {
      std::vector<int> nodeMap(n);
      for (int p = 0; p < n; ++p) nodeMap[p] = idOf(p);
      check(ex_put_node_num_map(exo_, nodeMap.data()), path, "ex_put_node_num_map");
    }
    // Elements grouped by block (Exodus numbers elements block after block); the element map
    // gives each element its particle's id + 1, so ParaView's ids are perinox's.
    std::vector<int> elemMap;
    for (int id : blockIds) {
      std::vector<int> conn;
      std::vector<double> attr;
      for (int p = 0; p < n; ++p) {
        if (block[p] != id) continue;
        conn.push_back(p + 1);
        elemMap.push_back(idOf(p));
        const double r = dim == 3 ? std::cbrt(3 * volume[p] / (4 * M_PI)) : std::sqrt(volume[p] / (M_PI * thickness));
        attr.push_back(r);
        attr.push_back(volume[p]);
      }
      check(ex_put_elem_block(exo_, id, "SPHERE", static_cast<int>(conn.size()), 1, 2), path, "ex_put_elem_block");
      check(ex_put_elem_conn(exo_, id, conn.data()), path, "ex_put_elem_conn");
      check(ex_put_elem_attr(exo_, id, attr.data()), path, "ex_put_elem_attr");
      Names an({"radius", "volume"});
      check(ex_put_attr_names(exo_, EX_ELEM_BLOCK, id, an.ptr.data()), path, "ex_put_attr_names");
      const std::string bname = "block_" + std::to_string(id);
      check(ex_put_name(exo_, EX_ELEM_BLOCK, id, bname.c_str()), path, "ex_put_name");
    }
    if (n > 0) check(ex_put_elem_num_map(exo_, elemMap.data()), path, "ex_put_elem_num_map");
    int setId = 1;
    for (const auto& [name, members] : nodeSets) {
      std::vector<int> nodes;
      for (int p : members) nodes.push_back(p + 1);
      check(ex_put_node_set_param(exo_, setId, static_cast<int>(nodes.size()), 0), path, "ex_put_node_set_param");
      if (!nodes.empty()) check(ex_put_node_set(exo_, setId, nodes.data()), path, "ex_put_node_set");
      check(ex_put_name(exo_, EX_NODE_SET, setId, name.c_str()), path, "ex_put_name");
      ++setId;
    }
    if (nodalVars_ > 0) {
      check(ex_put_var_param(exo_, "n", static_cast<int>(nodalVars_)), path, "ex_put_var_param");
      Names nn(nodalNames);
      check(ex_put_var_names(exo_, "n", static_cast<int>(nodalVars_), nn.ptr.data()), path, "ex_put_var_names");
    }
    if (globalVars_ > 0) {
      check(ex_put_var_param(exo_, "g", static_cast<int>(globalVars_)), path, "ex_put_var_param");
      Names gn(globalNames);
      check(ex_put_var_names(exo_, "g", static_cast<int>(globalVars_), gn.ptr.data()), path, "ex_put_var_names");
    }
    check(ex_update(exo_), path, "ex_update");
  } catch (...) {
    ex_close(exo_);
    exo_ = -1;
    throw;
  }
}

ExodusWriter::~ExodusWriter() {
  if (exo_ >= 0) ex_close(exo_);
}

void ExodusWriter::writeStep(double time, const std::vector<std::vector<double>>& nodal, const std::vector<double>& globals) {
  if (exo_ < 0) throw std::runtime_error("the Exodus file '" + path_ + "' is closed");
  if (nodal.size() != nodalVars_ || globals.size() != globalVars_)
    throw std::logic_error("ExodusWriter::writeStep: wrong number of variables for '" + path_ + "'");
  const int step = steps_ + 1;  // Exodus time steps count from 1
  check(ex_put_time(exo_, step, &time), path_, "ex_put_time");
  for (std::size_t v = 0; v < nodalVars_; ++v) {
    if (nodal[v].size() != particles_) throw std::logic_error("ExodusWriter::writeStep: a nodal variable has the wrong length");
    check(ex_put_nodal_var(exo_, step, static_cast<int>(v + 1), static_cast<int>(particles_), nodal[v].data()), path_,
          "ex_put_nodal_var");
  }
  if (globalVars_ > 0)
    check(ex_put_glob_vars(exo_, step, static_cast<int>(globalVars_), globals.data()), path_, "ex_put_glob_vars");
  check(ex_update(exo_), path_, "ex_update");
  steps_ = step;
}

void ExodusWriter::close() {
  if (exo_ < 0) return;
  const int rc = ex_close(exo_);
  exo_ = -1;
  check(rc, path_, "ex_close");
}

#endif

}  // namespace perinox
