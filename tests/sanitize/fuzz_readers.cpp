// Fuzzes perinox's file readers in-process, for a build with AddressSanitizer and
// UndefinedBehaviorSanitizer (tests/sanitize/CMakeLists.txt): every case writes a mesh or a
// particle file, damaged in one way, and reads it. A reader may refuse a file (a std::exception
// whose sentence is one line naming the file) or read it; it must never touch memory it does not
// own (the sanitizers abort the run and name the access), never throw anything else, never hang.
//
//   fuzz_readers DIR [--seed S] [--cases N]
//
// Exodus cases start from the meshes of tests/exodus/ExodusTestMeshes.hpp and change one thing:
// an element type, block or set name or the title, of random length (up to 6 000 characters)
// and bytes, random bytes of the file overwritten, the file cut short or extended with garbage,
// node numbers out of range, huge coordinates. Particle-file cases change one line: long
// tokens, NUL and control bytes, hexadecimal, nan and inf, overflowing numbers, too many or too
// few columns, invalid UTF-8. Case K of seed S is always the same case. Prints a tally and
// `N passed, M failed` (a failure is an exception that is not std::exception-derived, or a
// refusal whose sentence holds control bytes or does not name the file).
#include <exodusII.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "ExodusTestMeshes.hpp"
#include "perinox/core/Discretization.hpp"
#include "perinox/core/ExodusMesh.hpp"

namespace {

using Rng = std::mt19937_64;

std::string randomText(Rng& rng, std::size_t length, bool anyByte) {
  std::string s(length, 'A');
  std::uniform_int_distribution<int> byte(anyByte ? 1 : 32, anyByte ? 255 : 126);
  for (char& c : s) c = static_cast<char>(byte(rng));
  return s;
}

std::size_t randomLength(Rng& rng) {
  static const std::size_t lengths[] = {0, 1, 31, 32, 33, 40, 80, 81, 200, 256, 257, 1000, 5000, 6000};
  return lengths[std::uniform_int_distribution<std::size_t>(0, std::size(lengths) - 1)(rng)];
}

exotest::Mesh baseMesh(Rng& rng, int& dim) {
  switch (std::uniform_int_distribution<int>(0, 4)(rng)) {
    case 0: dim = 3; return exotest::hexBox(3, 2, 2, 0.5, 2);
    case 1: dim = 3; return exotest::tets();
    case 2: dim = 2; return exotest::quads();
    case 3: dim = 3; return exotest::spheres();
    default: dim = 3; return exotest::wedge();
  }
}

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void spill(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Writes one damaged mesh; returns what was done to it.
std::string exodusCase(Rng& rng, const std::string& path, int& dim) {
  exotest::Mesh m = baseMesh(rng, dim);
  const int kind = std::uniform_int_distribution<int>(0, 8)(rng);
  std::string what;
  std::size_t rewritten = 0;  // kinds 0 and 8: the length of the type name or title written after the mesh
  switch (kind) {
    case 0: rewritten = randomLength(rng); what = "element type of " + std::to_string(rewritten) + " bytes"; break;
    case 1: {
      const std::size_t n = std::min<std::size_t>(randomLength(rng), 80);  // the writer's name length
      m.blocks[0].name = randomText(rng, n, rng() % 2);
      what = "block name of " + std::to_string(n) + " bytes";
      break;
    }
    case 2:
      if (!m.nodeSets.empty()) m.nodeSets[0].name = randomText(rng, std::min<std::size_t>(randomLength(rng), 80), rng() % 2);
      what = "node set name";
      break;
    case 3:
      for (int& n : m.blocks[0].conn)
        if (rng() % 4 == 0) n = static_cast<int>(rng() % 3 == 0 ? -n : n * 1000 + static_cast<int>(rng() % 7));
      what = "node numbers out of range";
      break;
    case 4:
      for (auto& x : m.nodes)
        if (rng() % 3 == 0) x[rng() % 3] = (rng() % 2 ? 1 : -1) * std::ldexp(1.0, 900 + static_cast<int>(rng() % 123));
      what = "huge coordinates";
      break;
    case 8: rewritten = randomLength(rng); what = "title of " + std::to_string(rewritten) + " bytes"; break;
    default: what = "bytes"; break;
  }
  try {
    exotest::write(path, m);
  } catch (const std::exception&) {
    // The writer itself refused (a name the library cannot store): write the undamaged mesh.
    exotest::Mesh plain = baseMesh(rng, dim);
    exotest::write(path, plain);
    what += " (not writable; undamaged)";
  }
  if (kind == 0 || kind == 8) {
    const std::string text = randomText(rng, rewritten, rng() % 2);
    if (kind == 0) exotest::setElementType(path, 1, text);
    else exotest::setTitle(path, text);
    return "exodus: " + what;
  }
  if (kind >= 5) {
    std::vector<char> bytes = slurp(path);
    if (kind == 5) {  // overwrite a few random bytes
      const int flips = 1 + static_cast<int>(rng() % 8);
      for (int k = 0; k < flips && !bytes.empty(); ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng());
      what = std::to_string(flips) + " bytes overwritten";
    } else if (kind == 6) {
      const std::size_t keep = bytes.empty() ? 0 : rng() % bytes.size();
      bytes.resize(keep);
      what = "cut at byte " + std::to_string(keep);
    } else {
      const std::string junk = randomText(rng, 1 + rng() % 4096, true);
      bytes.insert(bytes.end(), junk.begin(), junk.end());
      what = "garbage appended";
    }
    spill(path, bytes);
  }
  return "exodus: " + what;
}

const char* kParticles =
    "# x y z volume block\n"
    "0 0 0 1 1\n1 0 0 1 1\n0 1 0 1 1\n1 1 0 1 1\n2 0 0 1 2\n2 1 0 1 2\n0 2 0 1 1\n1 2 0 1 1\n2 2 0 1 2\n";

std::string particleCase(Rng& rng, const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(kParticles);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const std::size_t at = 1 + rng() % (lines.size() - 1);
  static const char* tokens[] = {"0x1p3", "nan", "inf", "-infinity", "1e999", "-1e-320", "1e-320", "1.0x", "--1",
                                 "1e", ".", "+", "9999999999999999999999", "2.5", "-3", "\xff\xfe", "\xc3(",
                                 "1\t2", "1e308"};
  std::string what;
  switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
    case 0: {
      std::istringstream ls(lines[at]);
      std::vector<std::string> f;
      for (std::string t; ls >> t;) f.push_back(t);
      f[rng() % f.size()] = tokens[rng() % std::size(tokens)];
      lines[at].clear();
      for (const auto& t : f) lines[at] += t + " ";
      what = "token";
      break;
    }
    case 1: lines[at] = randomText(rng, randomLength(rng), true); what = "random line"; break;
    case 2: lines[at] += std::string(1, '\0') + "7"; what = "NUL byte"; break;
    case 3: lines[at] = std::string(100000, '1') + " 0 0 1"; what = "100 000-digit number"; break;
    case 4: lines[at] += " 1 2 3 4 5 6"; what = "too many columns"; break;
    default: lines[at] = "1 2"; what = "too few columns"; break;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  for (const auto& l : lines) out << l << '\n';
  return "particle file: " + what + " at line " + std::to_string(at + 1);
}

long peakKilobytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}
constexpr long kMaxGrowthKb = 256 * 1024;

/// A refusal is one line of printable text that names the file (bytes of a damaged file are
/// shown escaped, never echoed).
bool goodSentence(const std::string& msg, const std::string& path) {
  for (unsigned char c : msg)
    if (c < 32 || c == 127) return false;
  return !msg.empty() && msg.find(path) != std::string::npos;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: fuzz_readers DIR [--seed S] [--cases N]\n";
    return 2;
  }
  const std::string dir = argv[1];
  unsigned long long seed = 1;
  int cases = 300;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--seed") seed = std::stoull(argv[i + 1]);
    else if (a == "--cases") cases = std::stoi(argv[i + 1]);
  }
  std::filesystem::create_directories(dir);
  ex_opts(0);
  int passed = 0, failed = 0, refused = 0, read = 0;
  for (int k = 0; k < cases; ++k) {
    Rng rng(seed * 1000003ull + static_cast<unsigned long long>(k));
    const bool exodus = k % 3 != 2;
    const std::string path = dir + "/case_" + std::to_string(k) + (exodus ? ".e" : ".txt");
    int dim = 2;
    const std::string what = exodus ? exodusCase(rng, path, dim) : particleCase(rng, path);
    std::string problem;
    const long before = peakKilobytes();
    try {
      if (exodus) (void)perinox::readExodusMesh(path, dim, 0.5);
      else (void)perinox::readParticleFile(path, 2, 1.5, 1.0, 1.0, true);
      ++read;
    } catch (const std::exception& e) {
      ++refused;
      if (!goodSentence(e.what(), path)) problem = "refusal is not one printable line naming the file";
    } catch (...) {
      problem = "threw something that is not a std::exception";
    }
    // A reader sizes what it allocates by the file: a damaged count in a file of a few kilobytes
    // must not make it take hundreds of megabytes (the peak only grows: measured per case).
    const long grown = peakKilobytes() - before;
    if (problem.empty() && grown > kMaxGrowthKb)
      problem = "the peak memory grew by " + std::to_string(grown / 1024) + " MB reading a file of " +
                std::to_string(std::filesystem::file_size(path) / 1024) + " kB";
    if (problem.empty()) {
      ++passed;
      std::filesystem::remove(path);
    } else {
      ++failed;
      std::cout << "FAIL case " << k << " (" << what << "): " << problem << " (kept " << path << ")\n";
    }
  }
  std::cout << "seed " << seed << ": " << read << " read, " << refused << " refused\n";
  std::cout << passed << " passed, " << failed << " failed\n";
  return failed == 0 ? 0 : 1;
}
