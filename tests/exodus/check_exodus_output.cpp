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
//   - with --pieces P, the run wrote one file per rank (fields.e.P.r, r zero-padded, and no
//     fields.e): the pieces are read as one data set through their node and element number maps
//     (each particle id in exactly one piece, every piece with the same time steps), as SEACAS's
//     epu or ParaView join them.
//   usage: check_exodus_output DIR [--probe NAME=REGION]... [--blocks ID,ID...] [--volume V] [--no-vtu] [--pieces P]
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
  int pieces = 0;  // 0: one file, fields.e
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
    } else if (arg == "--pieces" && a + 1 < argc) {
      o.pieces = std::stoi(argv[++a]);
    } else if (arg == "--volume" && a + 1 < argc) {
      o.wantVolume = std::stod(argv[++a]);
    } else {
      std::cerr << "unknown argument " << arg << "\n";
      return false;
    }
  }
  return true;
}

/// One file of the results: its Exodus id and, for each of its nodes, the particle id (0-based).
struct Piece {
  int exo = -1, nodes = 0, nblocks = 0, nsets = 0;
  std::vector<int> id;
};

/// The results as one data set (one file, or the pieces joined by their number maps): particle
/// positions by id.
struct Mesh {
  std::vector<Piece> pieces;
  int dim = 0, nodes = 0;
  std::vector<double> X, Y, Z;
};

/// Opens one file and reads its header, its nodes' ids (the node number map: identity for a
/// file without one) and their positions into m (by id).
bool openPiece(const std::string& path, Mesh& m) {
  int cpu = sizeof(double), io = 0;
  float version = 0;
  Piece p;
  p.exo = ex_open(path.c_str(), EX_READ, &cpu, &io, &version);
  if (p.exo < 0) {
    fail("cannot open " + path);
    return false;
  }
  ex_set_max_name_length(p.exo, 80);  // the writer's name length (region names beyond 32 characters)
  char title[MAX_LINE_LENGTH + 1];
  int dim = 0, elems = 0, nside = 0;
  ex_get_init(p.exo, title, &dim, &p.nodes, &elems, &p.nblocks, &p.nsets, &nside);
  if (elems != p.nodes) fail(path + " has " + std::to_string(elems) + " elements for " + std::to_string(p.nodes) + " nodes");
  m.dim = dim;
  p.id.assign(p.nodes, 0);
  if (p.nodes > 0) ex_get_node_num_map(p.exo, p.id.data());
  std::vector<double> x(p.nodes), y(p.nodes), z(p.nodes);
  if (p.nodes > 0) ex_get_coord(p.exo, x.data(), y.data(), dim == 3 ? z.data() : nullptr);
  for (int k = 0; k < p.nodes; ++k) {
    const int g = --p.id[k];  // 1-based in the file
    if (g < 0) {
      fail(path + ": node " + std::to_string(k + 1) + " maps to particle " + std::to_string(g));
      continue;
    }
    if (g >= static_cast<int>(m.X.size())) m.X.resize(g + 1, NAN), m.Y.resize(g + 1, NAN), m.Z.resize(g + 1, NAN);
    m.X[g] = x[k], m.Y[g] = y[k], m.Z[g] = z[k];
  }
  m.nodes += p.nodes;
  m.pieces.push_back(p);
  return true;
}

/// Blocks: every particle once, as a sphere, whose element number maps to its particle; the
/// block ids and the volume as asked.
void checkBlocks(const Mesh& m, const Options& o) {
  std::vector<int> seen(m.nodes, 0);
  std::set<int> blocks;
  double volume = 0;
  for (const Piece& p : m.pieces) {
    std::vector<int> ids(p.nblocks), elemMap(p.nodes);
    ex_get_elem_blk_ids(p.exo, ids.data());
    if (p.nodes > 0) ex_get_elem_num_map(p.exo, elemMap.data());
    int element = 0;
    for (int id : ids) {
      char type[MAX_STR_LENGTH + 1];
      int n = 0, per = 0, attrs = 0;
      ex_get_elem_block(p.exo, id, type, &n, &per, &attrs);
      if (std::string(type) != "SPHERE" || per != 1 || attrs != 2) fail("block " + std::to_string(id) + " is not a block of spheres");
      std::vector<int> conn(n);
      std::vector<double> attr(2 * n);
      if (n > 0) ex_get_elem_conn(p.exo, id, conn.data()), ex_get_elem_attr(p.exo, id, attr.data());
      for (int e = 0; e < n; ++e, ++element) {
        const int g = p.id[conn[e] - 1];
        if (g < 0 || g >= m.nodes) continue;
        ++seen[g];
        if (elemMap[element] != g + 1) fail("element " + std::to_string(element + 1) + " maps to " + std::to_string(elemMap[element]) +
                                            ", its node to particle " + std::to_string(g));
        volume += attr[2 * e + 1];
      }
      if (!o.wantBlocks.empty() && !o.wantBlocks.count(id)) fail("unexpected block id " + std::to_string(id));
      blocks.insert(id);
    }
  }
  for (int g = 0; g < m.nodes; ++g)
    if (seen[g] != 1) fail("particle " + std::to_string(g) + " is in " + std::to_string(seen[g]) + " elements");
  if (!o.wantBlocks.empty() && blocks != o.wantBlocks) fail("wrong block ids");
  if (o.wantVolume > 0 && std::abs(volume - o.wantVolume) > 1e-12 * o.wantVolume)
    fail("the spheres' volumes sum to " + std::to_string(volume) + ", not " + std::to_string(o.wantVolume));
}

/// The nodal variables by name (the same in every piece), read at a time step by particle id.
struct Nodal {
  const Mesh& m;
  std::vector<std::string> names;
  explicit Nodal(const Mesh& mesh) : m(mesh) {
    for (std::size_t k = 0; k < m.pieces.size(); ++k) {
      int nvars = 0;
      ex_get_var_param(m.pieces[k].exo, "n", &nvars);
      std::vector<std::vector<char>> buf(nvars, std::vector<char>(257, 0));
      std::vector<char*> ptr;
      for (auto& b : buf) ptr.push_back(b.data());
      ex_get_var_names(m.pieces[k].exo, "n", nvars, ptr.data());
      const std::vector<std::string> got(ptr.begin(), ptr.end());
      if (k == 0) names = got;
      else if (got != names) fail("the pieces have different nodal variables");
    }
  }
  std::vector<double> operator()(int step, const std::string& n) const {
    std::vector<double> v(m.nodes, NAN);
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k] == n) {
        for (const Piece& p : m.pieces) {
          std::vector<double> local(p.nodes);
          if (p.nodes > 0) ex_get_nodal_var(p.exo, step, static_cast<int>(k) + 1, p.nodes, local.data());
          for (int i = 0; i < p.nodes; ++i) v[p.id[i]] = local[i];
        }
        return v;
      }
    fail("no nodal variable " + n);
    return v;
  }
};

/// Node sets by name, as 1-based particle numbers (id + 1), over the pieces.
std::map<std::string, std::vector<int>> nodeSets(const Mesh& m) {
  std::map<std::string, std::vector<int>> sets;
  for (const Piece& p : m.pieces) {
    std::vector<int> setIds(p.nsets);
    if (p.nsets > 0) ex_get_node_set_ids(p.exo, setIds.data());
    for (int id : setIds) {
      int n = 0, df = 0;
      ex_get_node_set_param(p.exo, id, &n, &df);
      std::vector<int> list(n);
      if (n > 0) ex_get_node_set(p.exo, id, list.data());
      auto& set = sets[name(p.exo, EX_NODE_SET, id)];
      for (int node : list) set.push_back(p.id[node - 1] + 1);
    }
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
    const double lf = srec[s - 1].at("load_factor");
    for (const Piece& p : m.pieces) {
      double t = 0;
      ex_get_time(p.exo, s, &t);
      if (std::abs(t - lf) > 1e-15) fail("time step " + std::to_string(s) + " has time " + std::to_string(t) + ", not the load factor");
    }
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
    std::cerr << "usage: check_exodus_output DIR [--probe NAME=REGION]... [--blocks ID,...] [--volume V] [--no-vtu] [--pieces P]\n";
    return 2;
  }
  const std::string& dir = o.dir;
  csvDir = dir;
  if (o.noVtu && (std::ifstream(dir + "/fields.pvtu") || std::ifstream(dir + "/fields_0.vtu"))) fail("VTU files were written");
  if (std::ifstream(dir + "/fields.e.tmp") || std::ifstream(dir + ".partial")) fail("a partial Exodus file or folder is left");
  ex_opts(0);
  Mesh m;
  std::vector<std::string> files;
  if (o.pieces == 0) {
    files.push_back(dir + "/fields.e");
  } else {
    if (std::ifstream(dir + "/fields.e")) fail("fields.e was written beside the per-rank pieces");
    const std::string p = std::to_string(o.pieces);
    for (int r = 0; r < o.pieces; ++r) {
      const std::string rs = std::to_string(r);
      files.push_back(dir + "/fields.e." + p + "." + std::string(p.size() - rs.size(), '0') + rs);
    }
    const std::string beyond = std::to_string(o.pieces);
    if (std::ifstream(dir + "/fields.e." + p + "." + beyond)) fail("more pieces than " + p);
  }
  for (const auto& f : files)
    if (!openPiece(f, m)) return 1;
  if (static_cast<int>(m.X.size()) != m.nodes) fail(std::to_string(m.nodes) + " nodes for particle ids up to " + std::to_string(m.X.size()));
  m.X.resize(m.nodes), m.Y.resize(m.nodes), m.Z.resize(m.nodes);
  checkBlocks(m, o);
  const Nodal nodal(m);
  const int steps = static_cast<int>(ex_inquire_int(m.pieces[0].exo, EX_INQ_TIME));
  for (const Piece& p : m.pieces)
    if (ex_inquire_int(p.exo, EX_INQ_TIME) != steps) fail("the pieces hold different numbers of time steps");
  std::ifstream sj(dir + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(sj);
  if (steps != static_cast<int>(summary.at("steps").size()))
    fail(std::to_string(steps) + " time steps in fields.e, " + std::to_string(summary.at("steps").size()) +
         " converged steps in summary.json");
  checkSteps(m, o, nodal, summary, steps);
  checkFieldsCsv(m, nodal, steps);
  for (const Piece& p : m.pieces) ex_close(p.exo);
  if (failures == 0)
    std::cout << "fields.e: " << files.size() << " file(s), " << steps << " time steps, " << m.nodes << " particles: equals fields.csv and summary.json\n";
  return failures == 0 ? 0 : 1;
}
