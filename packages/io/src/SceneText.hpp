#pragma once
// The scene file as text, checked before Teuchos parses it: readable, not empty, UTF-8 without
// control characters, and well-formed XML of the shape a scene has (one <ParameterList> root
// holding <ParameterList> and empty <Parameter> elements, no text between them). Private to io.
#include <cstddef>
#include <string>

namespace perinox {

/// A user's text for a message: in single quotes, control and non-ASCII bytes shown as \xNN,
/// cut to `max` characters with "..." so that no value can make a message long.
std::string quote(const std::string& s, std::size_t max = 40);

/// Empty if t is UTF-8 text without NUL or control bytes (tab, CR, LF allowed); else what is
/// wrong ("a NUL byte", ...), with `line` the 1-based line where.
std::string textProblem(const std::string& t, int& line);

/// The scene file's bytes with a UTF-8 byte-order mark removed. Throws SceneError (naming the
/// file and, where there is one, the line) on a directory, an unreadable, empty or oversized
/// file, a NUL or other control byte, bytes that are not UTF-8, and XML that is not well-formed
/// or not shaped like a scene.
std::string readSceneText(const std::string& path);

/// The file's bytes with the checks of readSceneText that do not depend on the format (a
/// readable file of at most 16 MiB, not empty, UTF-8 without control bytes): for YAML.
std::string readInputText(const std::string& path);

}  // namespace perinox
