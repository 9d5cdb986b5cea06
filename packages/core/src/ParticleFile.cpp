// Particle files: one particle per line, "x y z volume [block]" ('#' starts a comment), or Peridigm's
// text files, "x y z block volume".
#include "perinox/core/Discretization.hpp"
#include "perinox/core/InputFile.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace perinox {

namespace {

[[noreturn]] void fail(const std::string& path, long line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

/// Parses a whole token as a double; false on trailing garbage ("1.0x") or no number at all.
/// Overflow ("1e999") parses to +-inf and is rejected later as non-finite.
bool parseDouble(const std::string& tok, double& out) {
  if (!decimalCharacters(tok)) return false;  // scenes' rule: no hexadecimal, nan or inf
  const char* s = tok.c_str();
  char* endp = nullptr;
  out = std::strtod(s, &endp);
  return endp != s && *endp == '\0';
}

/// A token for a message: printable, cut to 40 characters.
std::string shown(const std::string& tok) { return printable(tok); }

/// d without particles, its scalars checked.
Discretization emptyParticleSet(const std::string& path, int dim, double horizon, double dx, double thickness) {
  if (dim < 1 || dim > 3)
    fail(path, 0, "dimension must be 1, 2 or 3 (got " + std::to_string(dim) + ")");
  if (!(horizon > 0.0) || !std::isfinite(horizon))
    fail(path, 0, "horizon must be positive and finite (got " + messageNumber(horizon) + ")");
  if (!(dx > 0.0) || !std::isfinite(dx))
    fail(path, 0, "nominal spacing dx must be positive and finite (got " + messageNumber(dx) + ")");
  if (!(thickness > 0.0) || !std::isfinite(thickness))
    fail(path, 0, "thickness must be positive and finite (got " + messageNumber(thickness) + ")");
  Discretization d;
  d.dim = dim;
  d.dx = dx;
  d.horizon = horizon;
  d.thickness = thickness;
  return d;
}

/// Appends the particle of one line (number lineNo) to d, if the line holds one. Columns
/// VolumeThenBlock: "x y z volume [block]", '#' starts a comment. BlockThenVolume (Peridigm's
/// text files): exactly "x y z block volume"; a line whose first character (after spaces) is '#',
/// '/' or '*' is a comment, as Peridigm reads them.
void parseLine(const std::string& path, long lineNo, std::string text, Discretization& d, ParticleColumns columns) {
  if (text.find('\0') != std::string::npos) fail(path, lineNo, "contains a NUL byte (a particle file is text)");
  const bool peridigm = columns == ParticleColumns::BlockThenVolume;
  const char* layout = peridigm ? "\"x y z block volume\"" : "\"x y z volume [block]\"";
  if (peridigm) {
    const std::size_t first = text.find_first_not_of(" \t\r");
    if (first != std::string::npos && (text[first] == '/' || text[first] == '*')) return;
  }
  const std::size_t hash = text.find('#');
  if (hash != std::string::npos) text.erase(hash);
  std::istringstream ls(text);
  std::string tok;
  double v[5];
  int n = 0;
  while (ls >> tok) {
    if (n == 5) fail(path, lineNo, std::string("too many columns (expected ") + layout + ")");
    if (!parseDouble(tok, v[n])) {
      char* end = nullptr;
      const double spelled = std::strtod(tok.c_str(), &end);  // nan, inf, infinity: a number, not finite
      if (end != tok.c_str() && *end == '\0' && !std::isfinite(spelled) && tok.find_first_of("xX") == std::string::npos)
        fail(path, lineNo, "'" + shown(tok) + "' is not a finite number");
      fail(path, lineNo, "'" + shown(tok) + "' is not a number (expected " + layout + ")");
    }
    if (!std::isfinite(v[n])) fail(path, lineNo, "'" + shown(tok) + "' is not a finite number");
    ++n;
  }
  if (n == 0) return;  // blank or comment-only line
  if (peridigm && n != 5)
    fail(path, lineNo, std::string("expected 5 numbers ") + layout + " (Peridigm's text file), found " + std::to_string(n));
  if (n < 4) fail(path, lineNo, std::string("expected at least 4 numbers ") + layout + ", found " + std::to_string(n));
  const double volume = peridigm ? v[4] : v[3];
  if (!(volume > 0.0)) fail(path, lineNo, "volume must be positive (got " + messageNumber(volume) + ")");
  if (volume < kSmallestVolume)
    fail(path, lineNo, "volume " + messageNumber(volume) + " is below " + messageNumber(kSmallestVolume) + " (products of two volumes would underflow)");
  int blk = 1;
  if (n == 5) {
    // Accept "2" and "2.0" but not "2.5": block ids are integers.
    const double b = peridigm ? v[3] : v[4];
    if (b != std::floor(b) || b < 0 || b > INT_MAX) fail(path, lineNo, "block id must be an integer of 0 or more (got " + messageNumber(b) + ")");
    blk = static_cast<int>(b);
  }
  if (static_cast<long long>(d.X.size()) >= kMaxParticles)
    fail(path, lineNo, "more than " + std::to_string(kMaxParticles) + " particles (the most perinox reads)");
  Vec3 x = Vec3::Zero();  // unused axes are present in the file but forced to 0
  for (int a = 0; a < d.dim; ++a) x[a] = v[a];
  d.X.push_back(x);
  d.volume.push_back(volume);
  d.block.push_back(blk);
}

/// The per-particle flags (a file has no fictitious particles and no lattice sides) and the box
/// of the particles read.
void finish(Discretization& d) {
  const std::size_t n = d.X.size();
  d.fictitious.assign(n, 0);
  d.sideMask.assign(n, 0);
  if (n == 0) return;
  d.boxLower = d.X[0];
  d.boxUpper = d.X[0];
  for (const Vec3& x : d.X) {
    d.boxLower = d.boxLower.cwiseMin(x);
    d.boxUpper = d.boxUpper.cwiseMax(x);
  }
}

std::ifstream openParticleFile(const std::string& path) {
  requireRegularFile(path, "particle file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, 0, "cannot open particle file for reading");
  return in;
}

}  // namespace

Discretization readParticleFile(const std::string& path, int dim, double horizon, double dx,
                                double thickness, bool families, ParticleColumns columns) {
  Discretization d = emptyParticleSet(path, dim, horizon, dx, thickness);
  std::ifstream in = openParticleFile(path);
  std::string text;
  long lineNo = 0;
  while (std::getline(in, text)) parseLine(path, ++lineNo, text, d, columns);
  if (in.bad()) fail(path, lineNo, "read error");
  if (d.X.empty()) fail(path, lineNo, "no particles in file");
  finish(d);
  if (families) buildFamilies(d);
  return d;
}

double particleFileSpacing(const std::string& path, int dim, double thickness, ParticleColumns columns) {
  // readParticleFile's parse, keeping only the volumes (8 bytes a particle, not a whole
  // discretisation: every rank of a distributed run reads the file here).
  Discretization d = emptyParticleSet(path, dim, 1.0, 1.0, thickness);  // horizon and spacing unused here
  std::ifstream in = openParticleFile(path);
  std::vector<double> volumes;
  std::string text;
  long lineNo = 0;
  while (std::getline(in, text)) {
    parseLine(path, ++lineNo, text, d, columns);
    if (!d.volume.empty()) {
      volumes.push_back(d.volume.back());
      d.X.clear();
      d.volume.clear();
      d.block.clear();
    }
  }
  if (in.bad()) fail(path, lineNo, "read error");
  if (volumes.empty()) fail(path, lineNo, "no particles in file");
  const auto mid = volumes.begin() + static_cast<std::ptrdiff_t>(volumes.size() / 2);
  std::nth_element(volumes.begin(), mid, volumes.end());
  const double cell = *mid / (dim == 3 ? 1.0 : thickness);  // 1D: a length, 2D: an area, 3D: a volume
  return dim == 1 ? cell : dim == 2 ? std::sqrt(cell) : std::cbrt(cell);
}

std::uint64_t particleFileSize(const std::string& path) {
  std::ifstream in = openParticleFile(path);
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  if (size < 0) fail(path, 0, "cannot tell the particle file's size");
  return static_cast<std::uint64_t>(size);
}

long particleFileNewlines(const std::string& path, std::uint64_t begin, std::uint64_t end) {
  std::ifstream in = openParticleFile(path);
  in.seekg(static_cast<std::streamoff>(begin));
  std::string chunk(static_cast<std::size_t>(end - begin), '\0');
  in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
  if (in.gcount() != static_cast<std::streamsize>(chunk.size())) fail(path, 0, "read error");
  long count = 0;
  for (char c : chunk) count += c == '\n';
  return count;
}

Discretization readParticleFileRange(const std::string& path, int dim, double horizon, double dx, double thickness,
                                     std::uint64_t begin, std::uint64_t end, long newlinesBefore, long* lastLine,
                                     ParticleColumns columns) {
  Discretization d = emptyParticleSet(path, dim, horizon, dx, thickness);
  if (lastLine) *lastLine = 0;
  if (begin >= end) {
    finish(d);
    return d;
  }
  std::ifstream in = openParticleFile(path);
  long lineNo = newlinesBefore + 1;  // the line holding byte `begin`
  std::uint64_t at = begin;
  if (begin > 0) {
    // The line holding byte `begin` belongs to this range only if it starts there.
    in.seekg(static_cast<std::streamoff>(begin - 1));
    char previous = '\0';
    in.get(previous);
    if (previous != '\n') {
      std::string rest;
      std::getline(in, rest);
      at += rest.size() + 1;
      ++lineNo;
    }
  }
  std::string text;
  while (at < end && std::getline(in, text)) {
    at += text.size() + 1;
    if (lastLine) *lastLine = lineNo;
    parseLine(path, lineNo++, text, d, columns);
  }
  if (in.bad()) fail(path, lineNo, "read error");
  finish(d);
  return d;
}

}  // namespace perinox
