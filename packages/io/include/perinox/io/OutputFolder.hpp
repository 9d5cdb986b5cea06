#pragma once
// Where a run may write, and how it replaces what is there. The policy (README, "Output
// folders"): results go into a new folder; an existing folder is replaced only if it is one that
// perinox wrote (it holds the marker file perinox writes into every folder it makes, listing the
// folder's entries) and holds nothing else, or if it is empty. Never a file, a symbolic link, a
// device, the root, the home folder, the current folder or a folder containing any of these, the
// scene or a checkpoint being resumed. A folder is written under a staging name beside it and
// renamed into place when complete, so it is whole or absent.
#include <stdexcept>
#include <string>
#include <vector>

namespace perinox {

/// A path the run may not write to, refused before any work: one sentence naming the option.
class OutputPathError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The marker file's name; its first line says what kind of folder it marks.
inline constexpr const char* kFolderMarker = ".perinox-folder";

enum class FolderKind { Output, Checkpoint };

/// A path someone else's data lives at, which the folder must neither be nor contain.
struct ProtectedPath {
  std::string path;
  std::string what;  // "the scene file", "the checkpoint to resume from", ...
};

/// A folder to be written: the target, the staging folder it is written in first, and the name
/// the previous target is moved to while the new one is renamed in.
struct FolderPlan {
  FolderKind kind = FolderKind::Output;
  std::string option;   // how the user named it: "--output 'out/x'"
  std::string target;   // normalised (no trailing slash)
  std::string staging;  // target + ".partial" (output) or ".writing" (checkpoint)
  std::string aside;    // target + ".old"
};

/// The names a folder at `path` is written under (trailing slashes dropped); checks nothing.
FolderPlan folderNames(const std::string& path, FolderKind kind, const std::string& optionName);

/// Checks that `path` may be written as a folder of the given kind under the policy above, and
/// that its parent can hold it (creating a probe folder in the nearest existing ancestor), without
/// writing anything else. Throws OutputPathError with one sentence otherwise.
FolderPlan planFolder(const std::string& path, FolderKind kind, const std::string& optionName,
                      const std::vector<ProtectedPath>& protectedPaths);

/// Refuses two plans that would overwrite each other (the same folder, or one inside the other).
void checkDistinct(const FolderPlan& a, const FolderPlan& b);

/// Creates the staging folder (and missing parents), replacing a stale staging folder of an
/// earlier run that was killed; marks it as perinox's.
void openStaging(const FolderPlan& plan);

/// Marks the staging folder with the list of its entries and renames it over the target (moved
/// aside first, removed once the new one is in place). The target is checked again first: if it
/// gained anything perinox did not write while the run went on, throws OutputPathError and leaves
/// the results in the staging folder.
void commitFolder(const FolderPlan& plan);

/// Whether `dir` is a folder perinox may replace as a folder of this kind (empty, or marked and
/// holding only what its marker lists); "" if so, else the reason, as the end of a sentence.
std::string whyNotReplaceable(const std::string& dir, FolderKind kind);

}  // namespace perinox
