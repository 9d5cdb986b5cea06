// The output-folder policy (see OutputFolder.hpp): what may be written where, and replacing a
// folder only as a whole and only when perinox wrote everything in it.
#include "perinox/io/OutputFolder.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace perinox {

namespace fs = std::filesystem;

namespace {

const char* markerHeader(FolderKind k) { return k == FolderKind::Output ? "perinox output" : "perinox checkpoint"; }
constexpr const char* kStagingHeader = "perinox staging";

/// A path as the user gave it, shortened for a message.
std::string shown(const std::string& p) {
  std::string s;
  for (unsigned char c : p) s += (c < 0x20 || c == 0x7f) ? '?' : static_cast<char>(c);
  return s.size() > 120 ? s.substr(0, 60) + "..." + s.substr(s.size() - 40) : s;
}

[[noreturn]] void refuse(const std::string& option, const std::string& why) { throw OutputPathError(option + ": " + why); }

/// The first line of a folder's marker, and the entries it lists ("" when there is no marker).
std::string readMarker(const fs::path& dir, std::set<std::string>* listed) {
  std::ifstream in(dir / kFolderMarker);
  if (!in) return "";
  std::string header, line;
  std::getline(in, header);
  while (std::getline(in, line))
    if (listed && !line.empty()) listed->insert(line);
  return header;
}

/// Files an earlier perinox, which wrote no marker, left in its folders of this kind.
bool legacyEntry(const std::string& name, FolderKind kind) {
  auto ends = [&](const char* suffix) {
    const std::size_t n = std::strlen(suffix);
    return name.size() >= n && name.compare(name.size() - n, n, suffix) == 0;
  };
  auto starts = [&](const char* prefix) { return name.rfind(prefix, 0) == 0; };
  if (kind == FolderKind::Checkpoint) return name == "state.json" || (starts("rank_") && ends(".txt"));
  return name == "scene.resolved.xml" || name == "summary.json" || name == "newton.csv" || name == "path.csv" ||
         name == "fields.csv" || name == "fields.pvtu" || name == "plot.log" || (starts("fields_") && ends(".vtu")) ||
         (starts("profile_") && ends(".csv")) || ends(".png");
}

bool inside(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i)
    if (i == inner.end() || *i != *o) return false;
  return true;
}

fs::path canonicalOf(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(p, ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

/// A folder's entries, or the reason they cannot be listed.
std::vector<std::string> entries(const fs::path& dir, std::string& error) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) names.push_back(it->path().filename().string());
  if (ec) error = ec.message();
  std::sort(names.begin(), names.end());
  return names;
}

/// "" when `p` is absent or a staging folder perinox made, else why it is in the way.
std::string whyNotStaging(const fs::path& p) {
  std::error_code ec;
  const auto st = fs::symlink_status(p, ec);
  if (ec || !fs::exists(st)) return "";
  if (fs::is_directory(st) && readMarker(p, nullptr) == kStagingHeader) return "";
  return "'" + shown(p.string()) + "' is in the way and is not a folder perinox is writing";
}

}  // namespace

namespace {

/// Removes `p` if it is absent, a staging folder of perinox's or a folder of the plan's kind that
/// perinox may replace; anything else is left alone and refused.
void removeOurs(const std::string& p, const FolderPlan& plan) {
  std::error_code ec;
  const auto st = fs::symlink_status(p, ec);
  if (ec || !fs::exists(st)) return;
  if (!whyNotStaging(p).empty() && !(fs::is_directory(st) && whyNotReplaceable(p, plan.kind).empty()))
    throw OutputPathError(plan.option + ": '" + shown(p) + "' appeared while the run went on and perinox did not write it; move it away");
  fs::remove_all(p);
}

}  // namespace

std::string whyNotReplaceable(const std::string& dirName, FolderKind kind) {
  const fs::path dir(dirName);
  std::string error;
  const auto names = entries(dir, error);
  if (!error.empty()) return "cannot be listed (" + error + ")";
  if (names.empty()) return "";
  std::set<std::string> listed;
  const std::string header = readMarker(dir, &listed);
  const bool marked = header == markerHeader(kind);
  if (!header.empty() && !marked)
    return "is a perinox " + std::string(header == kStagingHeader ? "folder still being written" : header.substr(8) + " folder") +
           ", not " + (kind == FolderKind::Output ? "an output" : "a checkpoint") + " folder";
  bool legacy = !marked;
  for (const auto& n : names) {
    if (n == kFolderMarker) continue;
    if (marked ? listed.count(n) == 0 : !legacyEntry(n, kind))
      return "holds '" + shown(n) + "', which perinox did not write there";
  }
  if (legacy && kind == FolderKind::Checkpoint && !std::count(names.begin(), names.end(), "state.json"))
    return "is not a perinox checkpoint folder";
  if (legacy && kind == FolderKind::Output && !std::count(names.begin(), names.end(), "summary.json"))
    return "is not a perinox output folder (no " + std::string(kFolderMarker) + " marker)";
  return "";
}

FolderPlan folderNames(const std::string& path, FolderKind kind, const std::string& optionName) {
  FolderPlan plan;
  plan.kind = kind;
  plan.option = optionName + " '" + shown(path) + "'";
  std::string clean = path;
  while (clean.size() > 1 && clean.back() == '/') clean.pop_back();
  plan.target = clean;
  plan.staging = clean + (kind == FolderKind::Output ? ".partial" : ".writing");
  plan.aside = clean + ".old";
  return plan;
}

FolderPlan planFolder(const std::string& path, FolderKind kind, const std::string& optionName,
                      const std::vector<ProtectedPath>& protectedPaths) {
  const FolderPlan plan = folderNames(path, kind, optionName);
  const std::string& opt = plan.option;
  const std::string& clean = plan.target;
  if (path.empty()) refuse(optionName, "needs a folder name");
  const fs::path given(clean);
  const std::string last = given.filename().string();
  if (clean == "/" ) refuse(opt, "is the root folder; name a new folder for the results");
  if (last == "." || last == "..") refuse(opt, "names the folder '.' or '..'; name a new folder for the results");
  const fs::path abs = fs::absolute(given).lexically_normal();
  const fs::path canon = canonicalOf(abs);
  std::error_code ec;
  const fs::path cwd = canonicalOf(fs::current_path(ec));
  if (canon == canon.root_path()) refuse(opt, "is the root folder; name a new folder for the results");
  if (!ec && inside(cwd, canon))
    refuse(opt, "is the current folder or contains it; name a new folder for the results");
  if (const char* home = std::getenv("HOME"); home && *home && inside(canonicalOf(home), canon))
    refuse(opt, "is the home folder or contains it; name a new folder for the results");
  for (const auto& pp : protectedPaths) {
    if (pp.path.empty()) continue;
    if (inside(canonicalOf(pp.path), canon))
      refuse(opt, "would replace " + pp.what + " '" + shown(pp.path) + "'; name another folder");
  }
  // Names: the longest one written is the target's with its staging or aside suffix.
  const long nameMax = [&] {
    fs::path a = abs.parent_path();
    while (!a.empty() && !fs::exists(a, ec) && a != a.root_path()) a = a.parent_path();
    const long n = pathconf(a.empty() ? "/" : a.c_str(), _PC_NAME_MAX);
    return n > 0 ? n : 255L;
  }();
  for (const auto& part : abs)
    if (static_cast<long>(part.string().size()) + 12 > nameMax)
      refuse(opt, "holds a name longer than this file system allows (" + std::to_string(nameMax - 12) + " characters at most)");
  if (abs.string().size() + 16 > PATH_MAX) refuse(opt, "is longer than this system allows");

  const auto st = fs::symlink_status(given, ec);
  if (fs::is_symlink(st)) refuse(opt, "is a symbolic link; perinox writes only into a new folder or replaces one it wrote");
  if (fs::exists(st) && !fs::is_directory(st))
    refuse(opt, std::string(fs::is_regular_file(st) ? "is a file" : "is a device or special file") +
                    ", not a folder; name a new folder for the results");
  if (fs::is_directory(st)) {
    const std::string why = whyNotReplaceable(clean, kind);
    if (!why.empty())
      refuse(opt, "exists and " + why + "; perinox replaces only a folder it wrote, so name a new folder or move it");
  }
  for (const auto& side : {plan.staging, plan.aside}) {
    std::string why = whyNotStaging(side);
    if (!why.empty() && side == plan.aside && fs::is_directory(fs::symlink_status(side, ec)) &&
        whyNotReplaceable(side, kind).empty())
      why.clear();  // a previous result moved aside by a run killed while renaming
    if (!why.empty()) refuse(opt, why + "; move it away");
  }
  // The nearest existing ancestor must be a folder in which folders can be made.
  fs::path anc = abs.parent_path();
  while (!anc.empty() && !fs::exists(fs::symlink_status(anc, ec)) && anc != anc.root_path()) anc = anc.parent_path();
  if (anc.empty()) anc = cwd;
  if (!fs::is_directory(anc, ec))
    refuse(opt, "cannot be made: '" + shown(anc.string()) + "' is a file, not a folder");
  const fs::path probe = anc / (".perinox-probe-" + std::to_string(getpid()));
  if (::mkdir(probe.c_str(), 0700) != 0)
    refuse(opt, "cannot be made: no folder can be created in '" + shown(anc.string()) + "' (" + std::strerror(errno) + ")");
  ::rmdir(probe.c_str());
  return plan;
}

void checkDistinct(const FolderPlan& a, const FolderPlan& b) {
  const fs::path pa = canonicalOf(a.target), pb = canonicalOf(b.target);
  if (inside(pa, pb) || inside(pb, pa))
    throw OutputPathError(b.option + " and " + a.option + " are the same folder or one holds the other; each needs its own folder");
}

void openStaging(const FolderPlan& plan) {
  const std::string why = whyNotStaging(plan.staging);
  if (!why.empty()) throw OutputPathError(plan.option + ": " + why + "; move it away");
  fs::remove_all(plan.staging);
  fs::create_directories(plan.staging);
  std::ofstream(fs::path(plan.staging) / kFolderMarker) << kStagingHeader << "\n";
}

void commitFolder(const FolderPlan& plan) {
  std::string error;
  const auto names = entries(plan.staging, error);
  if (!error.empty()) throw OutputPathError(plan.option + ": the staging folder '" + shown(plan.staging) + "' cannot be listed (" + error + ")");
  {
    std::ostringstream m;
    m << markerHeader(plan.kind) << "\n";
    for (const auto& n : names)
      if (n != kFolderMarker) m << n << "\n";
    const fs::path marker = fs::path(plan.staging) / kFolderMarker;
    std::ofstream out(marker, std::ios::trunc);
    out << m.str();
    if (!out) throw OutputPathError(plan.option + ": cannot write '" + shown(marker.string()) + "'");
  }
  std::error_code ec;
  const auto st = fs::symlink_status(plan.target, ec);
  if (fs::exists(st)) {
    const std::string why = fs::is_directory(st) && !fs::is_symlink(st) ? whyNotReplaceable(plan.target, plan.kind)
                                                                        : std::string("is no longer a folder");
    if (!why.empty())
      throw OutputPathError(plan.option + " changed while the run went on (" + why + "): the results are in '" +
                            shown(plan.staging) + "'");
    removeOurs(plan.aside, plan);
    fs::rename(plan.target, plan.aside);
  }
  fs::rename(plan.staging, plan.target);
  removeOurs(plan.aside, plan);
}

}  // namespace perinox
