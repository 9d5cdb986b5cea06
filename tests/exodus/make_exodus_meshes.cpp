// Writes the Exodus meshes the driver tests run on (tests/exodus/exodus_tests.cmake) into a
// folder:
//   bar.e, bar_points.txt   a two-block hex bar (block 1: x < L/2, block 2: x > L/2) with node
//                           sets "left"/"right", and the same particles as a particle file,
//                           computed here from the closed form (centre (i+1/2) h, volume h^3),
//                           not by the reader
//   quad.e, quad_points.txt a 2D plate of quads, the same for a 2D scene (volume h^2 x 0.5, the
//                           scene's thickness)
//   bimaterial_bar.e        a 40 x 4 x 4 hex bar in two blocks, for the two-material bar
//   inverted.e, flat_tet.e, pyramid.e, no_blocks.e, sphere_no_volume.e, not_exodus.e
//                           meshes the reader must refuse
//   usage: make_exodus_meshes DIR
#include <cstdio>
#include <string>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <iterator>

#include "ExodusTestMeshes.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_exodus_meshes DIR\n";
    return 1;
  }
  const std::string dir = argv[1];
  try {
    // The bar: 16 x 4 x 4 hexahedra of edge 0.25 (L = 4, section 1 x 1), split at x = 2.
    const int nx = 16, ny = 4, nz = 4;
    const double h = 0.25;
    exotest::write(dir + "/bar.e", exotest::hexBox(nx, ny, nz, h, nx / 2));
    {
      std::ofstream out(dir + "/bar_points.txt");
      out << std::setprecision(17) << "# x y z volume block: the particles of bar.e in closed form\n";
      // The same order as the mesh (block 1, then block 2; k, j, i ascending): not needed by
      // perinox, which matches nothing by order, but it keeps the particle ids equal.
      for (int pass = 0; pass < 2; ++pass)
        for (int k = 0; k < nz; ++k)
          for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
              if ((i < nx / 2) != (pass == 0)) continue;
              out << (i + 0.5) * h << ' ' << (j + 0.5) * h << ' ' << (k + 0.5) * h << ' ' << h * h * h << ' ' << pass + 1 << '\n';
            }
    }
    // The 2D plate: 20 x 5 quads of edge 0.1 (two blocks split at x = 1), thickness from the scene.
    {
      exotest::Mesh m;
      m.dim = 2;
      const int qx = 20, qy = 5;
      const double q = 0.1;
      auto node = [&](int i, int j) { return 1 + i + (qx + 1) * j; };
      for (int j = 0; j <= qy; ++j)
        for (int i = 0; i <= qx; ++i) m.nodes.push_back({i * q, j * q, 0});
      exotest::Block b1(1, "QUAD4", 4, {}), b2(2, "QUAD4", 4, {});
      std::ofstream out(dir + "/quad_points.txt");
      out << std::setprecision(17) << "# x y z volume block (volume = area x 0.5, quad_exodus.xml's Thickness)\n";
      for (int pass = 0; pass < 2; ++pass)
        for (int j = 0; j < qy; ++j)
          for (int i = 0; i < qx; ++i) {
            if ((i < qx / 2) != (pass == 0)) continue;
            auto& b = pass == 0 ? b1 : b2;
            for (int n : {node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)}) b.conn.push_back(n);
            out << (i + 0.5) * q << ' ' << (j + 0.5) * q << " 0 " << q * q * 0.5 << ' ' << pass + 1 << '\n';
          }
      m.blocks = {b1, b2};
      exotest::NodeSet left{1, "left", {}}, right{2, "right", {}};
      for (int j = 0; j <= qy; ++j) {
        left.nodes.push_back(node(0, j));
        right.nodes.push_back(node(qx, j));
      }
      m.nodeSets = {left, right};
      exotest::write(dir + "/quad.e", m);
    }
    // The two-material bar of blocks_exodus_bar (tests/exodus/bimaterial_bar_exodus.xml): 40 x 4 x 4
    // hexahedra of edge 0.05 (L = 2, section 0.2 x 0.2), blocks 1 ('left part', x < 1) and 2.
    exotest::write(dir + "/bimaterial_bar.e", exotest::hexBox(40, 4, 4, 0.05, 20));
    // bar.e in netCDF-4 (HDF5), which the reader reads as it reads classic files; and cut short.
    exotest::write(dir + "/bar_netcdf4.e", exotest::hexBox(nx, ny, nz, h, nx / 2), true);
    {
      std::ifstream in(dir + "/bar_netcdf4.e", std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      std::ofstream(dir + "/bar_netcdf4_cut.e", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    }
    {  // the classic bar.e cut to two thirds: its header declares data beyond the end
      std::ifstream in(dir + "/bar.e", std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      std::ofstream(dir + "/bar_cut.e", std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
    }
    // bar.e's counts with another edge: another body that a checkpoint must not resume on.
    exotest::write(dir + "/bar_scaled.e", exotest::hexBox(nx, ny, nz, 0.26, nx / 2));
    exotest::write(dir + "/inverted.e", exotest::invertedHex());
    exotest::write(dir + "/flat_tet.e", exotest::flatTet());
    exotest::write(dir + "/pyramid.e", exotest::pyramid());
    exotest::write(dir + "/no_blocks.e", exotest::noBlocks());
    exotest::write(dir + "/sphere_no_volume.e", exotest::sphereWithoutVolume());
    std::ofstream(dir + "/not_exodus.e") << "this is a text file, not a mesh\n";
    // Untrusted files: an element type name longer than Exodus' 32 characters (the library copies
    // it whole into a fixed buffer), a duplicated element, a negative block id, and an element far
    // from the others (no neighbour within the horizon).
    for (int length : {40, 200, 5000}) {
      const std::string path = dir + "/long_type_" + std::to_string(length) + ".e";
      exotest::write(path, exotest::hexBox(2, 1, 1, 1.0, 9));
      exotest::setElementType(path, 1, "HEX8" + std::string(static_cast<std::size_t>(length - 4), 'X'));
    }
    {
      exotest::Mesh m = exotest::hexBox(4, 2, 2, 0.25, 9);
      auto& conn = m.blocks[0].conn;
      conn.insert(conn.end(), conn.begin(), conn.begin() + 8);  // element 1 again, as the last one
      exotest::write(dir + "/duplicate_element.e", m);
    }
    {  // a sphere mesh whose second and fourth elements sit on one node
      exotest::Mesh m = exotest::hexBox(4, 2, 2, 0.25, 9);
      exotest::Mesh balls;
      balls.nodes = m.nodes;
      balls.nodeSets = m.nodeSets;
      std::vector<int> conn;
      std::vector<double> attr;
      for (int n = 1; n <= static_cast<int>(m.nodes.size()); ++n) conn.push_back(n), attr.push_back(0.1), attr.push_back(0.25 * 0.25 * 0.25);
      conn.push_back(2), attr.push_back(0.1), attr.push_back(0.25 * 0.25 * 0.25);
      balls.blocks = {{1, "SPHERE", 1, conn, "balls", 2, attr}};
      exotest::write(dir + "/spheres_one_node.e", balls);
    }
    {
      exotest::Mesh m = exotest::hexBox(4, 2, 2, 0.25, 2);
      m.blocks[1].id = -3;
      exotest::write(dir + "/negative_block.e", m);
    }
    {
      exotest::Mesh m = exotest::hexBox(16, 4, 4, 0.25, 8);
      const int first = static_cast<int>(m.nodes.size()) + 1;
      for (int k = 0; k < 2; ++k)  // a unit-edge cube of edge 0.25 at x = 100: the stray element
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) m.nodes.push_back({100 + 0.25 * i, 0.25 * j, 0.25 * k});
      for (int n : {0, 1, 3, 2, 4, 5, 7, 6}) m.blocks[1].conn.push_back(first + n);
      exotest::write(dir + "/stray_element.e", m);
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}
