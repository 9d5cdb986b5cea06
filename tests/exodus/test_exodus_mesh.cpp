// The Exodus II mesh reader (packages/core/src/ExodusMesh.cpp) on meshes written here with the
// Exodus C API, against closed-form volumes, centroids and node-set contents
// (ExodusTestMeshes.hpp states each), on every MPI rank (each rank writes and reads its own
// files); the bad meshes it must refuse; and Peridigm's tensile_test.g against the particle
// file of the same model (tensile_bar_points.txt).
#include <gtest/gtest.h>
#define OMPI_SKIP_MPICXX 1  // the C API only (the C++ bindings warn under -Wextra)
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "ExodusTestMeshes.hpp"
#include "perinox/core/ExodusMesh.hpp"

using perinox::ExodusMesh;
using perinox::readExodusMesh;
using perinox::Vec3;

namespace {

int rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

/// A file name private to this process (ranks run the same tests at once).
std::string tmp(const std::string& name) {
  return "exodus_test_" + std::to_string(getpid()) + "_" + std::to_string(rank()) + "_" + name;
}

ExodusMesh writeAndRead(const std::string& name, const exotest::Mesh& m, int dim, double thickness = 1.0) {
  const std::string path = tmp(name);
  exotest::write(path, m);
  ExodusMesh out = readExodusMesh(path, dim, thickness);
  std::remove(path.c_str());
  return out;
}

/// The message of the reader's refusal of mesh m ("" if it accepted it).
std::string refusal(const std::string& name, const exotest::Mesh& m, int dim) {
  const std::string path = tmp(name);
  exotest::write(path, m);
  std::string msg;
  try {
    readExodusMesh(path, dim, 1.0);
  } catch (const std::runtime_error& e) {
    msg = e.what();
  }
  std::remove(path.c_str());
  return msg;
}

// Closed-form values are exact in binary or nearly so; the reader sums 8 (hex) or 6 (wedge)
// quadrature terms, so a few ulps of the element's size: 1e-13 relative.
constexpr double kTol = 1e-13;

}  // namespace

TEST(ExodusMesh, HexBoxTwoBlocksVolumesCentroidsSets) {
  const int nx = 4, ny = 2, nz = 2;
  const double h = 0.5;
  const ExodusMesh m = writeAndRead("hex.e", exotest::hexBox(nx, ny, nz, h, 2), 3);
  const auto& d = m.disc;
  ASSERT_EQ(d.size(), nx * ny * nz);
  ASSERT_EQ(m.blocks.size(), 2u);
  EXPECT_EQ(m.blocks[0].name, "left part");
  // Elements in file order: block 1 (i < 2) then block 2, each k, j, i ascending.
  int p = 0;
  for (int pass = 0; pass < 2; ++pass)
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          if ((i < 2) != (pass == 0)) continue;
          const Vec3 c((i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h);
          EXPECT_LT((d.X[p] - c).norm(), kTol) << "particle " << p;
          EXPECT_NEAR(d.volume[p], h * h * h, kTol * h * h * h);
          EXPECT_EQ(d.block[p], pass + 1);
          ++p;
        }
  // Node set "left" (x = 0): the elements with i = 0 (Peridigm's rule: an element touching a node).
  ASSERT_EQ(m.nodeSets.size(), 2u);
  EXPECT_EQ(m.nodeSets[0].name, "left");
  ASSERT_EQ(m.nodeSets[0].particles.size(), static_cast<std::size_t>(ny * nz));
  for (int q : m.nodeSets[0].particles) EXPECT_NEAR(d.X[q][0], 0.5 * h, kTol);
  for (int q : m.nodeSets[1].particles) EXPECT_NEAR(d.X[q][0], (nx - 0.5) * h, kTol);
  ASSERT_EQ(m.sideSets.size(), 1u);
  EXPECT_EQ(m.sideSets[0].particles, m.nodeSets[1].particles);  // the right face's elements
  // Nominal spacing: the edge of the (uniform) elements.
  EXPECT_NEAR(d.dx, h, kTol);
}

TEST(ExodusMesh, FrustumHexExactVolume) {
  const ExodusMesh m = writeAndRead("frustum.e", exotest::frustum(), 3);
  ASSERT_EQ(m.disc.size(), 1);
  EXPECT_NEAR(m.disc.volume[0], 7.0 / 3.0, kTol);
  EXPECT_LT((m.disc.X[0] - Vec3(1, 1, 0.5)).norm(), kTol);  // the corners' mean
  EXPECT_EQ(m.disc.block[0], 7);
}

TEST(ExodusMesh, TetrahedraAndNodeSet) {
  const ExodusMesh m = writeAndRead("tets.e", exotest::tets(), 3);
  const auto& d = m.disc;
  ASSERT_EQ(d.size(), 7);
  double cube = 0;
  for (int p = 0; p < 6; ++p) {
    EXPECT_NEAR(d.volume[p], 1.0 / 6.0, kTol);
    cube += d.volume[p];
  }
  EXPECT_NEAR(cube, 1.0, kTol);
  EXPECT_NEAR(d.volume[6], 4.0, kTol);
  EXPECT_LT((d.X[6] - Vec3(10.5, 0.75, 1.0)).norm(), kTol);
  EXPECT_EQ(d.block[6], 2);
  EXPECT_EQ(m.blocks[0].name, "block_1");  // unnamed: Peridigm's default name
  EXPECT_EQ(m.blocks[1].name, "corner");
  ASSERT_EQ(m.nodeSets.size(), 1u);
  EXPECT_EQ(m.nodeSets[0].particles, (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

TEST(ExodusMesh, Wedge) {
  const ExodusMesh m = writeAndRead("wedge.e", exotest::wedge(), 3);
  ASSERT_EQ(m.disc.size(), 1);
  EXPECT_NEAR(m.disc.volume[0], 1.0, kTol);
  EXPECT_LT((m.disc.X[0] - Vec3(1.0 / 3, 1.0 / 3, 1.0)).norm(), kTol);
}

TEST(ExodusMesh, QuadsAndTriangleTimesThickness) {
  const double t = 0.1;
  const ExodusMesh m = writeAndRead("quads.e", exotest::quads(), 2, t);
  const auto& d = m.disc;
  ASSERT_EQ(d.size(), 8);
  for (int p = 0; p < 6; ++p) EXPECT_NEAR(d.volume[p], 0.25 * t, kTol);
  EXPECT_LT((d.X[0] - Vec3(0.25, 0.25, 0)).norm(), kTol);
  EXPECT_NEAR(d.volume[6], 1.5 * t, kTol);
  EXPECT_LT((d.X[6] - Vec3(11, 0.5, 0)).norm(), kTol);
  EXPECT_NEAR(d.volume[7], 3 * t, kTol);
  EXPECT_LT((d.X[7] - Vec3(20 + 2.0 / 3.0, 1, 0)).norm(), 1e-12 * 20);
  EXPECT_EQ(m.nodeSets[0].particles, (std::vector<int>{0, 1, 2}));
  EXPECT_NEAR(d.dx, 0.5, kTol);  // median area 0.25
}

TEST(ExodusMesh, SpheresGiveParticlesDirectly) {
  const ExodusMesh m = writeAndRead("spheres.e", exotest::spheres(), 3);
  ASSERT_EQ(m.disc.size(), 3);
  const double written[3] = {0.1, 0.2, 0.3};
  for (int p = 0; p < 3; ++p) {
    EXPECT_EQ(m.disc.volume[p], written[p]);  // the attribute, as written
    EXPECT_EQ(m.disc.X[p], Vec3(p, 0, 0));
  }
  EXPECT_EQ(m.nodeSets[0].particles, std::vector<int>{2});
  EXPECT_EQ(m.nodeSets[0].name, "nodelist_1");  // unnamed: Peridigm's default name
  ASSERT_EQ(m.nodeSets.size(), 2u);
  EXPECT_EQ(m.nodeSets[1].name, "a node set name longer than thirty-two characters");  // not cut to 32
  EXPECT_EQ(m.nodeSets[1].particles, (std::vector<int>{0, 1}));
}

TEST(ExodusMesh, RefusesBadMeshesWithOneSentence) {
  auto expectRefused = [](const std::string& name, const exotest::Mesh& mesh, int dim, const std::string& phrase) {
    const std::string msg = refusal(name, mesh, dim);
    EXPECT_NE(msg.find(tmp(name)), std::string::npos) << msg;  // names the file
    EXPECT_NE(msg.find(phrase), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  };
  expectRefused("inverted.e", exotest::invertedHex(), 3, "element 2 of element block 1 ('left part') ('HEX8') is inverted");
  expectRefused("flat.e", exotest::flatTet(), 3, "element 1 of element block 1 ('TETRA') has zero volume");
  expectRefused("pyramid.e", exotest::pyramid(), 3, "'PYRAMID5' with 5 nodes, which perinox does not read");
  expectRefused("noblocks.e", exotest::noBlocks(), 3, "has no element blocks");
  expectRefused("sphere1.e", exotest::sphereWithoutVolume(), 3, "1 attribute(s)");
  expectRefused("quads3d.e", exotest::quads(), 3, "is a 2D mesh but the scene is 3D");
  expectRefused("hex2d.e", exotest::frustum(), 2, "has 3D elements ('HEX') but the scene is 2D");
  // Not an Exodus file, and no file at all.
  const std::string text = tmp("text.e");
  std::ofstream(text) << "x y z volume\n";
  try {
    readExodusMesh(text, 3, 1.0);
    ADD_FAILURE() << "a text file was read as a mesh";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(text + ": is not an Exodus II file"), std::string::npos) << e.what();
  }
  std::remove(text.c_str());
  try {
    readExodusMesh(tmp("absent.e"), 3, 1.0);
    ADD_FAILURE() << "a missing file was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open the Exodus mesh"), std::string::npos) << e.what();
  }
}

/// The mesh read in `parts` element ranges (readExodusMeshRange, one process) equals the whole
/// read: each range holds its elements' positions, volumes and blocks in file order, every block,
/// and each set's members in its range (global element numbers); the ranges' node ranges split
/// the nodes. The tensile test's mesh when it is here (three blocks, six node sets, elements
/// whose nodes lie in another range's node range), else the two-block hex box.
void expectRangesEqualWhole(const std::string& path, int dim, int parts) {
  const ExodusMesh whole = readExodusMesh(path, dim, 1.0);
  const perinox::ExodusMeshSize size = perinox::exodusMeshSize(path, dim);
  ASSERT_EQ(size.elements, whole.disc.size());
  std::vector<Vec3> X;
  std::vector<double> V;
  std::vector<int> B;
  std::vector<std::vector<int>> nodeSets(whole.nodeSets.size()), sideSets(whole.sideSets.size());
  int phases = 0;
  for (int r = 0; r < parts; ++r) {
    const perinox::ExodusRange range{size.elements * r / parts, size.elements * (r + 1) / parts, size.nodes * r / parts,
                                     size.nodes * (r + 1) / parts};
    const ExodusMesh part = perinox::readExodusMeshRange(path, dim, 1.0, range, [&](const std::function<void()>& f) {
      ++phases;
      f();
    });
    ASSERT_EQ(part.disc.size(), range.elementEnd - range.elementBegin);
    ASSERT_EQ(part.blocks.size(), whole.blocks.size());
    X.insert(X.end(), part.disc.X.begin(), part.disc.X.end());
    V.insert(V.end(), part.disc.volume.begin(), part.disc.volume.end());
    B.insert(B.end(), part.disc.block.begin(), part.disc.block.end());
    ASSERT_EQ(part.nodeSets.size(), whole.nodeSets.size());
    ASSERT_EQ(part.sideSets.size(), whole.sideSets.size());
    for (std::size_t s = 0; s < nodeSets.size(); ++s)
      for (int q : part.nodeSets[s].particles) {
        EXPECT_TRUE(q >= range.elementBegin && q < range.elementEnd) << "set " << s << " member " << q;
        nodeSets[s].push_back(q);
      }
    for (std::size_t s = 0; s < sideSets.size(); ++s)
      sideSets[s].insert(sideSets[s].end(), part.sideSets[s].particles.begin(), part.sideSets[s].particles.end());
  }
  EXPECT_EQ(phases, 3 * parts);  // header, elements, sets: each through the caller's phase
  ASSERT_EQ(static_cast<int>(X.size()), whole.disc.size());
  for (int p = 0; p < whole.disc.size(); ++p) {
    EXPECT_EQ(X[p], whole.disc.X[p]) << "particle " << p;  // the same arithmetic: bit for bit
    EXPECT_EQ(V[p], whole.disc.volume[p]) << "particle " << p;
    EXPECT_EQ(B[p], whole.disc.block[p]) << "particle " << p;
  }
  for (std::size_t s = 0; s < nodeSets.size(); ++s) EXPECT_EQ(nodeSets[s], whole.nodeSets[s].particles) << "node set " << s;
  for (std::size_t s = 0; s < sideSets.size(); ++s) EXPECT_EQ(sideSets[s], whole.sideSets[s].particles) << "side set " << s;
}

TEST(ExodusMesh, RangesReadPieceByPieceEqualTheWholeRead) {
  const std::string path = tmp("ranges.e");
  exotest::write(path, exotest::hexBox(6, 3, 2, 0.5, 3));
  for (int parts : {1, 2, 3, 5, 36}) expectRangesEqualWhole(path, 3, parts);
  std::remove(path.c_str());
#ifdef PERINOX_TENSILE_DIR
  for (int parts : {2, 7}) expectRangesEqualWhole(std::string(PERINOX_TENSILE_DIR) + "/tensile_test.g", 3, parts);
#endif
}

// A bad coordinate is found by the range whose node range holds it, a bad element by the range
// holding the element: each with the whole read's sentence.
TEST(ExodusMesh, ARangeRefusesWhatTheWholeReadRefuses) {
  const std::string path = tmp("ranges_inverted.e");
  exotest::write(path, exotest::invertedHex());
  const perinox::ExodusMeshSize size = perinox::exodusMeshSize(path, 3);
  ASSERT_EQ(size.elements, 2);
  auto identity = [](const std::function<void()>& f) { f(); };
  EXPECT_NO_THROW(perinox::readExodusMeshRange(path, 3, 1.0, {0, 1, 0, size.nodes}, identity));
  try {
    perinox::readExodusMeshRange(path, 3, 1.0, {1, 2, 0, 0}, identity);
    ADD_FAILURE() << "the inverted element was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("element 2 of element block 1"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

#ifdef PERINOX_TENSILE_DIR
// Peridigm's tensile test: the mesh read here against the particle file written from the same
// model (shared/benchmarks/README.md). The text file prints 10 significant digits, so it holds
// each value to half a unit in its 10th digit: 5e-10 relative. That, not 1e-12, is the most a
// comparison with it can show; positions are compared to 5e-10 of their magnitude (plus 1e-15 cm
// for coordinates that are zero).
TEST(ExodusMesh, TensileTestMatchesParticleFile) {
  const std::string dir = PERINOX_TENSILE_DIR;
  const ExodusMesh m = readExodusMesh(dir + "/tensile_test.g", 3, 1.0);
  std::ifstream in(dir + "/tensile_bar_points.txt");
  ASSERT_TRUE(in) << dir;
  struct Row {
    Vec3 x;
    double v;
    int block;
  };
  std::vector<Row> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    Row r;
    ls >> r.x[0] >> r.x[1] >> r.x[2] >> r.v >> r.block;
    rows.push_back(r);
  }
  const auto& d = m.disc;
  ASSERT_EQ(static_cast<std::size_t>(d.size()), rows.size());
  ASSERT_EQ(m.blocks.size(), 3u);
  ASSERT_EQ(m.nodeSets.size(), 6u);
  // Match by position: the file's order is not the mesh's. Key: coordinates rounded to 1e-6 cm
  // (the spacing is 0.0635 cm; the two sources differ by < 1e-8 cm).
  auto key = [](const Vec3& x) {
    return std::make_tuple(std::llround(x[0] * 1e6), std::llround(x[1] * 1e6), std::llround(x[2] * 1e6));
  };
  std::map<std::tuple<long long, long long, long long>, int> byPos;
  for (int p = 0; p < d.size(); ++p) ASSERT_TRUE(byPos.emplace(key(d.X[p]), p).second) << "two particles at one place";
  double worstX = 0, worstV = 0;
  std::vector<int> seen(d.size(), 0);
  for (const Row& r : rows) {
    auto it = byPos.find(key(r.x));
    ASSERT_NE(it, byPos.end()) << "no mesh particle at " << r.x.transpose();
    const int p = it->second;
    ++seen[p];
    for (int a = 0; a < 3; ++a) {
      const double err = std::abs(d.X[p][a] - r.x[a]);
      EXPECT_LE(err, 5e-10 * std::abs(r.x[a]) + 1e-15) << "particle " << p << " axis " << a;
      worstX = std::max(worstX, err / (std::abs(r.x[a]) + 1e-300));
    }
    const double ev = std::abs(d.volume[p] - r.v) / r.v;
    EXPECT_LE(ev, 5e-10) << "particle " << p;
    worstV = std::max(worstV, ev);
    EXPECT_EQ(d.block[p], r.block) << "particle " << p;
  }
  for (int p = 0; p < d.size(); ++p) EXPECT_EQ(seen[p], 1) << "particle " << p;
  if (rank() == 0) std::printf("tensile_test.g vs tensile_bar_points.txt: worst relative position %.2e, volume %.2e\n", worstX, worstV);
}
#endif

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (rank() != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int rc = RUN_ALL_TESTS();
  int worst = 0;
  MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return worst;
}
