#pragma once
// Checks shared by the readers of input files (particle files, Exodus meshes): what a file must
// be before it is opened, and the one number syntax of scenes and particle files.
#include <filesystem>
#include <stdexcept>
#include <sstream>
#include <string>
#include <system_error>

namespace perinox {

/// Throws std::runtime_error("<path>: <why>") unless path names a regular file (or a link to
/// one). Checked before opening: opening a FIFO waits for a writer, and a folder or a device
/// would be read as garbage. `kind` names the file in the sentence ("particle file").
inline void requireRegularFile(const std::string& path, const std::string& kind) {
  if (path.empty()) throw std::runtime_error("the " + kind + " path is empty");
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st))
    throw std::runtime_error(path + ": cannot open the " + kind + " for reading (no such file, or not readable)");
  if (std::filesystem::is_directory(st)) throw std::runtime_error(path + ": is a folder, not a " + kind);
  if (!std::filesystem::is_regular_file(st))
    throw std::runtime_error(path + ": is not a regular file (a FIFO, device or socket), so it is not read as a " + kind);
}

/// True when `text` is written with the characters of a decimal number only (digits, sign,
/// point, exponent): no hexadecimal, no nan, inf or infinity. The same rule for scenes and
/// particle files; strtod then reads the number and the caller checks that it used every
/// character.
inline bool decimalCharacters(const std::string& text) {
  return !text.empty() && text.find_first_not_of("+-.0123456789eE") == std::string::npos;
}

/// A number as messages show it: ten significant digits, shortest form ("0.1", "2e+11").
inline std::string messageNumber(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

/// Text read from a file as a message may show it: bytes outside printable ASCII as \xNN, at
/// most 40 characters (then "...").
inline std::string printable(const std::string& text) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned char c : text) {
    if (out.size() >= 40) return out + "...";
    if (c >= 32 && c < 127) out += static_cast<char>(c);
    else out += std::string("\\x") + hex[c >> 4] + hex[c & 15];
  }
  return out;
}

/// The most particles perinox builds or reads: lattice sites (fictitious layers included), lines of
/// a particle file, elements of a mesh. A mesh's header is checked against it before anything is
/// sized by its counts (a netCDF-4 file may declare a dimension far larger than the file).
constexpr long long kMaxParticles = 50000000;

/// The smallest particle volume a reader accepts: below it the products of two volumes that
/// every bond force carries underflow to zero (1e-150 m^3 is far below any physical particle).
constexpr double kSmallestVolume = 1e-150;

}  // namespace perinox
