// A check of a classic netCDF file's header (CDF-1, CDF-2 and CDF-5, the formats Exodus II files
// are written in) against the file's length, before the netCDF library reads it: the library
// allocates what a header declares (a damaged count in a file of 2 kB made it touch 3.5 GB), and
// the Exodus reader sizes its arrays by the dimensions. After this check every count in the
// header and every fixed-size variable fits within the file.
//
// The format (netCDF's "classic format specification"), big-endian throughout:
//   header   = magic numrecs dim_list gatt_list var_list
//   list     = ABSENT (two zero words) | tag nelems [entry ...]   (tags 0x0A dim, 0x0B var, 0x0C att)
//   name     = nelems bytes, padded to 4
//   dim      = name length                      (length 0: the record dimension)
//   att      = name nc_type nelems values, padded to 4
//   var      = name nelems [dimid ...] att_list nc_type vsize begin
// Counts (nelems, lengths, numrecs, vsize, dimids) are 4 bytes, 8 in CDF-5; begin is 4 bytes in
// CDF-1, 8 in CDF-2 and CDF-5.
#include "NetcdfHeader.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <vector>

namespace perinox {

namespace {

class HeaderReader {
 public:
  HeaderReader(std::vector<unsigned char> bytes, std::uint64_t fileSize, int version)
      : b_(std::move(bytes)), fileSize_(fileSize), version_(version) {}

  std::uint64_t word(int size) {
    need(static_cast<std::uint64_t>(size));
    std::uint64_t v = 0;
    for (int k = 0; k < size; ++k) v = (v << 8) | b_[at_++];
    return v;
  }
  std::uint64_t count() { return word(version_ == 5 ? 8 : 4); }
  std::uint64_t offset() { return word(version_ == 1 ? 4 : 8); }
  /// Skips n bytes padded to 4, which must lie within the header read.
  void skip(std::uint64_t n) {
    const std::uint64_t padded = n + (4 - n % 4) % 4;
    need(padded);
    at_ += static_cast<std::size_t>(padded);
  }
  /// A count of entries each at least `least` bytes long: at most what the rest can hold.
  std::uint64_t entries(std::uint64_t least) {
    const std::uint64_t n = count();
    if (n > (b_.size() - at_) / least) throw std::runtime_error("its header declares more entries than the file holds");
    return n;
  }
  std::uint64_t fileSize() const { return fileSize_; }

 private:
  void need(std::uint64_t n) {
    if (n > b_.size() - at_) throw std::runtime_error("its header is truncated or declares more than the file holds");
  }
  std::vector<unsigned char> b_;
  std::size_t at_ = 4;  // after the magic
  std::uint64_t fileSize_;
  int version_;
};

std::uint64_t typeSize(std::uint64_t t) {
  switch (t) {
    case 1: case 2: case 7: return 1;   // byte, char, ubyte
    case 3: case 8: return 2;           // short, ushort
    case 4: case 5: case 9: return 4;   // int, float, uint
    case 6: case 10: case 11: return 8; // double, int64, uint64
    default: throw std::runtime_error("its header names an unknown data type " + std::to_string(t));
  }
}

void readAttributes(HeaderReader& r) {
  const std::uint64_t tag = r.count(), n = r.entries(12);
  if (n > 0 && tag != 0x0C) throw std::runtime_error("its header has a damaged attribute list");
  for (std::uint64_t a = 0; a < n; ++a) {
    r.skip(r.entries(1));  // the name
    const std::uint64_t size = typeSize(r.count());
    const std::uint64_t values = r.count();
    if (values > std::numeric_limits<std::uint64_t>::max() / size) throw std::runtime_error("its header declares an attribute larger than the file");
    r.skip(values * size);
  }
}

}  // namespace

void checkClassicNetcdfHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot be opened");
  const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0);
  // The header is at the start; read at most 64 MiB of it (Exodus headers are a few kB).
  const std::uint64_t take = std::min<std::uint64_t>(size, 64ull << 20);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(take));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(take));
  if (take < 4 || bytes[0] != 'C' || bytes[1] != 'D' || bytes[2] != 'F') throw std::runtime_error("is not a classic netCDF file");
  const int version = bytes[3];
  if (version != 1 && version != 2 && version != 5) throw std::runtime_error("has an unknown netCDF version " + std::to_string(version));
  HeaderReader r(std::move(bytes), size, version);
  (void)r.count();  // numrecs
  // Dimensions.
  std::uint64_t tag = r.count();
  const std::uint64_t dims = r.entries(8);
  if (dims > 0 && tag != 0x0A) throw std::runtime_error("its header has a damaged dimension list");
  std::vector<std::uint64_t> length(static_cast<std::size_t>(dims));
  for (auto& l : length) {
    r.skip(r.entries(1));
    l = r.count();
  }
  readAttributes(r);  // global attributes
  // Variables: every fixed-size one must lie within the file.
  tag = r.count();
  const std::uint64_t vars = r.entries(16);
  if (vars > 0 && tag != 0x0B) throw std::runtime_error("its header has a damaged variable list");
  for (std::uint64_t v = 0; v < vars; ++v) {
    r.skip(r.entries(1));
    const std::uint64_t rank = r.entries(4);
    bool record = false;
    long double bytes = 1;
    for (std::uint64_t k = 0; k < rank; ++k) {
      const std::uint64_t id = r.count();
      if (id >= dims) throw std::runtime_error("its header names a dimension that does not exist");
      if (length[static_cast<std::size_t>(id)] == 0) record = true;  // the record dimension
      else bytes *= static_cast<long double>(length[static_cast<std::size_t>(id)]);
    }
    readAttributes(r);
    bytes *= static_cast<long double>(typeSize(r.count()));
    (void)r.count();  // vsize (capped at 2^32 - 4 for large variables: not used)
    const std::uint64_t begin = r.offset();
    if (!record && static_cast<long double>(begin) + bytes > static_cast<long double>(r.fileSize()))
      throw std::runtime_error("is truncated, or its header declares data beyond its end");
  }
}

}  // namespace perinox
