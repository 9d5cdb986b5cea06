// Checks of the scene file as bytes and as XML text, before Teuchos parses it: Teuchos' parser
// accepts text between elements and elements inside a <Parameter>, stops at a NUL byte, and
// reports its own failures in several lines of its internals.
#include "SceneText.hpp"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <vector>

#include "perinox/io/Scene.hpp"

namespace perinox {

namespace {

constexpr std::size_t kMaxSceneBytes = std::size_t(16) << 20;

std::string hexByte(unsigned char c) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%02X", c);
  return b;
}

/// Length of the UTF-8 sequence starting at t[i] (a byte >= 0x80), or 0 if it is not one
/// (stray continuation byte, overlong form, surrogate, beyond U+10FFFF, cut short).
std::size_t utf8Length(const std::string& t, std::size_t i) {
  const auto at = [&](std::size_t k) { return i + k < t.size() ? static_cast<unsigned char>(t[i + k]) : 0u; };
  const unsigned c = at(0);
  std::size_t len = 0;
  unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) len = 2;
  else if (c >= 0xE0 && c <= 0xEF) len = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
  else if (c >= 0xF0 && c <= 0xF4) len = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
  else return 0;
  if (at(1) < lo || at(1) > hi) return 0;
  for (std::size_t k = 2; k < len; ++k)
    if (at(k) < 0x80 || at(k) > 0xBF) return 0;
  return len;
}

[[noreturn]] void failAt(const std::string& path, int line, const std::string& what) {
  throw SceneError(path + ":" + std::to_string(line) + ": " + what);
}

/// A scanner for the XML subset a scene uses, with line numbers for its messages.
class XmlShape {
 public:
  XmlShape(const std::string& text, const std::string& path) : t_(text), path_(path) {}

  void check() {
    while (i_ < t_.size()) {
      if (t_[i_] != '<') {
        text();
      } else if (at("<!--")) {
        const std::size_t end = t_.find("--", i_ + 4);
        if (end != std::string::npos && t_.compare(end, 3, "-->") != 0) {
          advance(end);
          fail("'--' inside a comment (XML allows it only in the closing '-->')");
        }
        skipPast("-->", "a comment");
      } else if (at("<?")) {
        if (rootSeen_) fail("a processing instruction '<?' after the root element");
        skipPast("?>", "the '<?' declaration");
      } else if (at("<!")) {
        fail("'<!' markup (DOCTYPE, CDATA) is not supported in a scene");
      } else if (at("</")) {
        closeTag();
      } else {
        openTag();
      }
    }
    if (!open_.empty())
      failAt(path_, open_.back().line, "malformed scene XML: <" + open_.back().tag + "> is never closed");
    if (!rootSeen_)
      throw SceneError(path_ + ": no <ParameterList> element: the file is empty or holds only white space or comments");
  }

 private:
  struct Open {
    std::string tag;
    int line;
  };

  [[noreturn]] void fail(const std::string& what) const { failAt(path_, line_, "malformed scene XML: " + what); }
  bool at(const char* s) const { return t_.compare(i_, std::strlen(s), s) == 0; }
  static bool space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

  void advance(std::size_t to) {
    for (; i_ < to; ++i_)
      if (t_[i_] == '\n') ++line_;
  }

  void skipPast(const char* end, const char* what) {
    const std::size_t e = t_.find(end, i_);
    if (e == std::string::npos) fail(std::string(what) + " is never closed");
    advance(e + std::strlen(end));
  }

  bool skipSpace() {
    const std::size_t from = i_;
    std::size_t e = i_;
    while (e < t_.size() && space(t_[e])) ++e;
    advance(e);
    return i_ > from;
  }

  std::string name() {
    const std::size_t from = i_;
    const auto ok = [&](char c, bool first) {
      return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == ':' ||
             (!first && (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.'));
    };
    while (i_ < t_.size() && ok(t_[i_], i_ == from)) ++i_;
    return t_.substr(from, i_ - from);
  }

  void expect(char c, const std::string& where) {
    if (i_ >= t_.size() || t_[i_] != c) fail("expected '" + std::string(1, c) + "' " + where);
    ++i_;
  }

  void text() {
    std::size_t e = t_.find('<', i_);
    if (e == std::string::npos) e = t_.size();
    std::size_t b = i_;
    while (b < e && space(t_[b])) ++b;
    advance(b);
    if (b < e) {
      std::size_t last = e;
      while (space(t_[last - 1])) --last;
      fail("text " + quote(t_.substr(b, last - b)) +
           (open_.empty() ? " outside the root element" : " inside <" + open_.back().tag + ">") +
           "; a scene holds only elements (values go in value=\"...\")");
    }
    advance(e);
  }

  void closeTag() {
    i_ += 2;
    const std::string tag = name();
    skipSpace();
    expect('>', "to end the closing tag </" + tag);
    if (open_.empty()) fail("closing tag </" + tag + "> without an opening tag");
    if (tag != open_.back().tag)
      fail("</" + tag + "> closes <" + open_.back().tag + "> opened at line " + std::to_string(open_.back().line));
    open_.pop_back();
    rootClosed_ = open_.empty();
  }

  void attributeValue(const std::string& attr) {
    if (i_ >= t_.size() || (t_[i_] != '"' && t_[i_] != '\'')) fail("the value of attribute '" + attr + "' must be in quotes");
    const char q = t_[i_++];
    const std::size_t e = t_.find(q, i_);
    if (e == std::string::npos) fail("the value of attribute '" + attr + "' is never closed");
    for (std::size_t k = i_; k < e; ++k) {
      if (t_[k] == '<') fail("'<' in the value of attribute '" + attr + "' (write &lt;)");
      if (t_[k] != '&') continue;
      const std::size_t semi = t_.find(';', k);
      const std::string ent = semi == std::string::npos || semi > e ? "" : t_.substr(k + 1, semi - k - 1);
      if (!entity(ent)) fail("'&' in the value of attribute '" + attr + "' must start an entity such as &amp;");
    }
    advance(e + 1);
  }

  static bool entity(const std::string& e) {
    static const std::set<std::string> named{"lt", "gt", "amp", "quot", "apos"};
    if (named.count(e)) return true;
    if (e.size() < 2 || e[0] != '#') return false;
    const bool hex = e[1] == 'x';
    const std::string digits = e.substr(hex ? 2 : 1);
    return !digits.empty() && digits.find_first_not_of(hex ? "0123456789abcdefABCDEF" : "0123456789") == std::string::npos;
  }

  void openTag() {
    const int startLine = line_;
    ++i_;
    const std::string tag = name();
    if (tag.empty()) fail("'<' that does not start an element");
    std::set<std::string> attrs;
    for (;;) {
      const bool spaced = skipSpace();
      if (at("/>") || at(">")) break;
      if (i_ >= t_.size()) fail("<" + tag + "> is cut off");
      const std::string attr = name();
      if (attr.empty() || !spaced) fail("unexpected character in <" + tag + ">");
      if (!attrs.insert(attr).second) fail("attribute '" + attr + "' is given twice in <" + tag + ">");
      skipSpace();
      expect('=', "after attribute '" + attr + "'");
      skipSpace();
      attributeValue(attr);
    }
    const bool empty = at("/>");
    i_ += empty ? 2 : 1;
    if (rootClosed_) fail("a second root element <" + tag + ">; a scene is one <ParameterList>");
    if (open_.empty()) {
      if (tag != "ParameterList") fail("the root element must be <ParameterList>, not <" + tag + ">");
    } else if (open_.back().tag == "Parameter") {
      fail("<" + tag + "> inside the <Parameter> opened at line " + std::to_string(open_.back().line) + "; a <Parameter> holds no elements");
    } else if (tag != "ParameterList" && tag != "Parameter") {
      fail("unexpected element <" + tag + ">; a scene holds only <ParameterList> and <Parameter> elements");
    }
    rootSeen_ = true;
    if (!empty) open_.push_back({tag, startLine});
  }

  const std::string& t_;
  const std::string& path_;
  std::size_t i_ = 0;
  int line_ = 1;
  std::vector<Open> open_;
  bool rootSeen_ = false, rootClosed_ = false;
};

}  // namespace

std::string quote(const std::string& s, std::size_t max) {
  std::string out;
  std::size_t chars = 0;
  for (unsigned char c : s) {
    const bool continuation = (c & 0xC0) == 0x80;  // keeps a UTF-8 character whole
    if (!continuation && chars++ == max) {
      out += "...";
      break;
    }
    if (c < 0x20 || c == 0x7F) out += "\\x" + hexByte(c).substr(2);
    else out += static_cast<char>(c);
  }
  return "'" + out + "'";
}

std::string textProblem(const std::string& t, int& line) {
  line = 1;
  for (std::size_t i = 0; i < t.size();) {
    const unsigned char c = t[i];
    if (c == '\n') ++line;
    if (c == 0) return "a NUL byte";
    if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7F) return "the control character " + hexByte(c);
    if (c < 0x80) {
      ++i;
      continue;
    }
    const std::size_t len = utf8Length(t, i);
    if (len == 0) return "the byte " + hexByte(c) + ", which is not UTF-8";
    i += len;
  }
  return "";
}

std::string readInputText(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw SceneError(path + ": cannot open the scene file (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw SceneError(path + ": is a directory, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open the scene file (" + std::strerror(errno) + ")");
  std::string text;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxSceneBytes)
      throw SceneError(path + ": the scene file is larger than 16 MiB (particles go in a 'Discretization/Particle File')");
  }
  if (in.bad()) throw SceneError(path + ": cannot read the scene file");
  if (text.empty()) throw SceneError(path + ": the scene file is empty");
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // UTF-8 byte-order mark
  int line = 0;
  const std::string problem = textProblem(text, line);
  if (!problem.empty()) failAt(path, line, "the scene file contains " + problem + "; a scene is UTF-8 text");
  return text;
}

std::string readSceneText(const std::string& path) {
  std::string text = readInputText(path);
  XmlShape(text, path).check();
  // Teuchos' parser reads character references only in decimal and below 256, while XML allows
  // any code point in decimal or hexadecimal (&#x4e2d;): write those beyond ASCII as the UTF-8
  // characters they stand for, and hexadecimal ones below 128 in decimal.
  for (std::size_t at = text.find("&#"); at != std::string::npos; at = text.find("&#", at + 1)) {
    const bool hex = at + 2 < text.size() && text[at + 2] == 'x';
    const std::size_t first = at + (hex ? 3 : 2), end = text.find(';', at);
    if (end == std::string::npos || end == first || end - first > 8) continue;
    const std::string digits = text.substr(first, end - first);
    if (digits.find_first_not_of(hex ? "0123456789abcdefABCDEF" : "0123456789") != std::string::npos) continue;
    const unsigned long cp = std::stoul(digits, nullptr, hex ? 16 : 10);
    std::string with;
    if (cp < 0x80) {
      if (!hex) continue;
      with = "&#" + std::to_string(cp) + ";";
    } else if (cp < 0x800) {
      with = {static_cast<char>(0xC0 | (cp >> 6)), static_cast<char>(0x80 | (cp & 0x3F))};
    } else if (cp < 0x10000) {
      if (cp >= 0xD800 && cp < 0xE000) continue;  // a surrogate is no character: Teuchos refuses it
      with = {static_cast<char>(0xE0 | (cp >> 12)), static_cast<char>(0x80 | ((cp >> 6) & 0x3F)),
              static_cast<char>(0x80 | (cp & 0x3F))};
    } else if (cp < 0x110000) {
      with = {static_cast<char>(0xF0 | (cp >> 18)), static_cast<char>(0x80 | ((cp >> 12) & 0x3F)),
              static_cast<char>(0x80 | ((cp >> 6) & 0x3F)), static_cast<char>(0x80 | (cp & 0x3F))};
    } else {
      continue;
    }
    text.replace(at, end - at + 1, with);
  }
  return text;
}

}  // namespace perinox
