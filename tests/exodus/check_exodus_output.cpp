// Checks a run's fields.e (Output/Format = Exodus or Both) with the Exodus C API against what
// the run wrote otherwise:
//   - one time step per converged load step of summary.json, time = the step's load factor;
//   - the last time step equals fields.csv (every particle: positions, displacements, stresses,
//     damage), to 1e-11 of each field's largest magnitude (fields.csv prints 12 significant
//     digits: half a unit in the 12th is 5e-12 of a value);
//   - at every time step, the mean displacement over the node set of each probe's region (the
//     scene's regions are written as node sets) equals summary.json's probe value at that step,
//     to 1e-12 of the probe's largest magnitude (both are doubles from the same state; the means
//     differ only by summation order);
//   - the element blocks hold every particle once, with the block ids given (--blocks), and
//     read back as sphere elements their volumes sum to --volume (when given).
//   - with --no-vtu, no VTU file was written (Output/Format = Exodus).
//   usage: check_exodus_output DIR [--probe NAME=REGION]... [--blocks ID,ID...] [--volume V] [--no-vtu]
#include <exodusII.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

int failures = 0;
void fail(const std::string& m) {
  std::cout << "CHECK FAILED: " << m << "\n";
  ++failures;
}

std::string csvDir;  // the run folder (fields.csv)

std::string name(int exo, ex_entity_type t, int id) {
  char buf[257] = {0};
  ex_get_name(exo, t, id, buf);
  return buf;
}

/// The command line.
struct Options {
  std::string dir;
  std::map<std::string, std::string> probeRegion;
  std::set<int> wantBlocks;
  double wantVolume = -1;
  bool noVtu = false;
};

bool parse(int argc, char** argv, Options& o) {
  if (argc < 2) return false;
  o.dir = argv[1];
  for (int a = 2; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--probe" && a + 1 < argc) {
      const std::string v = argv[++a];
      o.probeRegion[v.substr(0, v.find('='))] = v.substr(v.find('=') + 1);
    } else if (arg == "--blocks" && a + 1 < argc) {
      std::stringstream ss(argv[++a]);
      std::string t;
      while (std::getline(ss, t, ',')) o.wantBlocks.insert(std::stoi(t));
    } else if (arg == "--no-vtu") {
      o.noVtu = true;
    } else if (arg == "--volume" && a + 1 < argc) {
      o.wantVolume = std::stod(argv[++a]);
    } else {
      std::cerr << "unknown argument " << arg << "\n";
      return false;
    }
  }
  return true;
}

/// The file's header and particle positions.
struct Mesh {
  int exo = -1, dim = 0, nodes = 0, elems = 0, nblocks = 0, nsets = 0, nside = 0;
  std::vector<double> X, Y, Z;
};

/// Blocks: every particle once, as a sphere; the block ids and the volume as asked.
void checkBlocks(const Mesh& m, const Options& o) {
  std::vector<int> ids(m.nblocks);
  ex_get_elem_blk_ids(m.exo, ids.data());
  std::vector<int> seen(m.nodes, 0);
  double volume = 0;
  for (int id : ids) {
    char type[MAX_STR_LENGTH + 1];
    int n = 0, per = 0, attrs = 0;
    ex_get_elem_block(m.exo, id, type, &n, &per, &attrs);
    if (std::string(type) != "SPHERE" || per != 1 || attrs != 2) fail("block " + std::to_string(id) + " is not a block of spheres");
    std::vector<int> conn(n);
    std::vector<double> attr(2 * n);
    ex_get_elem_conn(m.exo, id, conn.data());
    ex_get_elem_attr(m.exo, id, attr.data());
    for (int e = 0; e < n; ++e) {
      ++seen[conn[e] - 1];
      volume += attr[2 * e + 1];
    }
    if (!o.wantBlocks.empty() && !o.wantBlocks.count(id)) fail("unexpected block id " + std::to_string(id));
  }
  for (int p = 0; p < m.nodes; ++p)
    if (seen[p] != 1) fail("particle " + std::to_string(p) + " is in " + std::to_string(seen[p]) + " elements");
  if (!o.wantBlocks.empty() && static_cast<std::size_t>(m.nblocks) != o.wantBlocks.size()) fail("wrong number of blocks");
  if (o.wantVolume > 0 && std::abs(volume - o.wantVolume) > 1e-12 * o.wantVolume)
    fail("the spheres' volumes sum to " + std::to_string(volume) + ", not " + std::to_string(o.wantVolume));
}

/// The nodal variables by name, read at a time step.
struct Nodal {
  const Mesh& m;
  std::vector<std::string> names;
  explicit Nodal(const Mesh& mesh) : m(mesh) {
    int nvars = 0;
    ex_get_var_param(m.exo, "n", &nvars);
    std::vector<std::vector<char>> buf(nvars, std::vector<char>(257, 0));
    std::vector<char*> ptr;
    for (auto& b : buf) ptr.push_back(b.data());
    ex_get_var_names(m.exo, "n", nvars, ptr.data());
    for (int v = 0; v < nvars; ++v) names.push_back(ptr[v]);
  }
  std::vector<double> operator()(int step, const std::string& n) const {
    std::vector<double> v(m.nodes);
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k] == n) {
        ex_get_nodal_var(m.exo, step, static_cast<int>(k) + 1, m.nodes, v.data());
        return v;
      }
    fail("no nodal variable " + n);
    return v;
  }
};

/// Node sets by name.
std::map<std::string, std::vector<int>> nodeSets(const Mesh& m) {
  std::map<std::string, std::vector<int>> sets;
  std::vector<int> setIds(m.nsets);
  if (m.nsets > 0) ex_get_node_set_ids(m.exo, setIds.data());
  for (int id : setIds) {
    int n = 0, df = 0;
    ex_get_node_set_param(m.exo, id, &n, &df);
    std::vector<int> list(n);
    if (n > 0) ex_get_node_set(m.exo, id, list.data());
    sets[name(m.exo, EX_NODE_SET, id)] = list;
  }
  return sets;
}

/// Every time step: its time is the step's load factor, and each probe's mean displacement over
/// its region's node set equals summary.json's.
void checkSteps(const Mesh& m, const Options& o, const Nodal& nodal, const nlohmann::json& summary, int steps) {
  const auto& srec = summary.at("steps");
  auto sets = nodeSets(m);
  const char* axes[3] = {"x", "y", "z"};
  for (int s = 1; s <= steps && s <= static_cast<int>(srec.size()); ++s) {
    double t = 0;
    ex_get_time(m.exo, s, &t);
    const double lf = srec[s - 1].at("load_factor");
    if (std::abs(t - lf) > 1e-15) fail("time step " + std::to_string(s) + " has time " + std::to_string(t) + ", not the load factor");
    for (const auto& [probe, region] : o.probeRegion) {
      if (!sets.count(region)) {
        fail("no node set named " + region);
        continue;
      }
      const auto& hist = summary.at("probes").at(probe);
      double big = 0;
      for (const auto& h : hist)
        for (double v : h.at("displacement")) big = std::max(big, std::abs(v));
      const auto& want = hist.at(s - 1).at("displacement");
      for (std::size_t c = 0; c < want.size(); ++c) {
        const auto u = nodal(s, std::string("displacement_") + axes[c]);
        double mean = 0;
        for (int node : sets[region]) mean += u[node - 1];
        mean /= static_cast<double>(sets[region].size());
        if (std::abs(mean - want[c].get<double>()) > 1e-12 * big)
          fail("step " + std::to_string(s) + ": probe " + probe + " component " + axes[c] + " is " + std::to_string(want[c].get<double>()) +
               " in summary.json but " + std::to_string(mean) + " from fields.e");
      }
    }
  }
}

/// The last step against fields.csv: id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,fictitious,damage.
void checkFieldsCsv(const Mesh& m, const Nodal& nodal, int steps) {
  const std::string& dir = csvDir;
  const int nodes = m.nodes;
  const auto& X = m.X;
  const auto& Y = m.Y;
  const auto& Z = m.Z;
  std::ifstream csv(dir + "/fields.csv");
  std::string line;
  std::getline(csv, line);
  const std::vector<std::string> cols{"", "", "", "", "displacement_x", "displacement_y", "displacement_z",
                                      "stress_xx", "stress_yy", "stress_zz", "stress_xy", "", "damage"};
  std::vector<std::vector<double>> last(cols.size());
  for (std::size_t c = 0; c < cols.size(); ++c)
    if (!cols[c].empty() && steps > 0) last[c] = nodal(steps, cols[c]);
  std::vector<double> scale(cols.size(), 0.0);
  for (std::size_t c = 0; c < cols.size(); ++c)
    for (double v : last[c]) scale[c] = std::max(scale[c], std::abs(v));
  int rows = 0;
  while (std::getline(csv, line)) {
    std::stringstream ls(line);
    std::vector<double> v;
    std::string t;
    while (std::getline(ls, t, ',')) v.push_back(std::stod(t));
    if (v.size() != cols.size()) {
      fail("bad fields.csv line: " + line);
      continue;
    }
    const int p = static_cast<int>(v[0]);
    if (p < 0 || p >= nodes) {
      fail("fields.csv has particle " + std::to_string(p) + ", fields.e " + std::to_string(nodes));
      continue;
    }
    ++rows;
    const double pos[3] = {X[p], Y[p], Z[p]};
    for (int a = 0; a < 3; ++a)
      if (std::abs(pos[a] - v[1 + a]) > 1e-11 * (std::abs(pos[a]) + 1e-300) + 1e-300 && std::abs(pos[a] - v[1 + a]) > 1e-11 * std::abs(v[1 + a]))
        fail("particle " + std::to_string(p) + " position differs");
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (cols[c].empty()) continue;
      if (std::abs(last[c][p] - v[c]) > 1e-11 * scale[c])
        fail("particle " + std::to_string(p) + " " + cols[c] + ": fields.e " + std::to_string(last[c][p]) + ", fields.csv " + std::to_string(v[c]));
    }
  }
  if (rows != nodes) fail(std::to_string(rows) + " rows in fields.csv, " + std::to_string(nodes) + " particles in fields.e");
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::cerr << "usage: check_exodus_output DIR [--probe NAME=REGION]... [--blocks ID,...] [--volume V] [--no-vtu]\n";
    return 2;
  }
  const std::string& dir = o.dir;
  csvDir = dir;
  if (o.noVtu && (std::ifstream(dir + "/fields.pvtu") || std::ifstream(dir + "/fields_0.vtu"))) fail("VTU files were written");
  if (std::ifstream(dir + "/fields.e.tmp") || std::ifstream(dir + ".partial")) fail("a partial Exodus file or folder is left");
  int cpu = sizeof(double), io = 0;
  float version = 0;
  ex_opts(0);
  Mesh m;
  m.exo = ex_open((dir + "/fields.e").c_str(), EX_READ, &cpu, &io, &version);
  if (m.exo < 0) {
    fail("cannot open " + dir + "/fields.e");
    return 1;
  }
  ex_set_max_name_length(m.exo, 80);  // the writer's name length (region names beyond 32 characters)
  char title[MAX_LINE_LENGTH + 1];
  ex_get_init(m.exo, title, &m.dim, &m.nodes, &m.elems, &m.nblocks, &m.nsets, &m.nside);
  m.X.assign(m.nodes, 0.0);
  m.Y.assign(m.nodes, 0.0);
  m.Z.assign(m.nodes, 0.0);
  ex_get_coord(m.exo, m.X.data(), m.Y.data(), m.dim == 3 ? m.Z.data() : nullptr);
  checkBlocks(m, o);
  const Nodal nodal(m);
  const int steps = static_cast<int>(ex_inquire_int(m.exo, EX_INQ_TIME));
  std::ifstream sj(dir + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(sj);
  if (steps != static_cast<int>(summary.at("steps").size()))
    fail(std::to_string(steps) + " time steps in fields.e, " + std::to_string(summary.at("steps").size()) +
         " converged steps in summary.json");
  checkSteps(m, o, nodal, summary, steps);
  checkFieldsCsv(m, nodal, steps);
  ex_close(m.exo);
  if (failures == 0)
    std::cout << "fields.e: " << steps << " time steps, " << m.nodes << " particles in " << m.nblocks
              << " block(s): equals fields.csv and summary.json\n";
  return failures == 0 ? 0 : 1;
}
