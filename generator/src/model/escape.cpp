#include "mbsgen/generator/model/escape.hpp"

#include <cstdio>
#include <set>

namespace mbsgen {

namespace {

// The length of the well-formed UTF-8 sequence starting at s[i] (RFC 3629, Table 3-7 of the
// Unicode standard), or 0 when the bytes there are not one.
std::size_t utf8_length(const std::string& s, std::size_t i) {
  auto byte = [&](std::size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
  const unsigned b0 = byte(i);
  if (b0 < 0x80) return 1;
  // A continuation byte at s[k] in [lo, hi] (byte() is 0 past the end: never one).
  auto cont = [&](std::size_t k, unsigned lo = 0x80, unsigned hi = 0xBF) {
    const unsigned b = byte(k);
    return b >= lo && b <= hi;
  };
  if (b0 >= 0xC2 && b0 <= 0xDF) return cont(i + 1) ? 2 : 0;
  if (b0 >= 0xE0 && b0 <= 0xEF) {
    const unsigned lo = b0 == 0xE0 ? 0xA0 : 0x80, hi = b0 == 0xED ? 0x9F : 0xBF;
    return cont(i + 1, lo, hi) && cont(i + 2) ? 3 : 0;
  }
  if (b0 >= 0xF0 && b0 <= 0xF4) {
    const unsigned lo = b0 == 0xF0 ? 0x90 : 0x80, hi = b0 == 0xF4 ? 0x8F : 0xBF;
    return cont(i + 1, lo, hi) && cont(i + 2) && cont(i + 3) ? 4 : 0;
  }
  return 0;
}

std::string hex_escape(unsigned char c) {
  char b[8];
  std::snprintf(b, sizeof b, "\\x%02x", c);
  return b;
}

}  // namespace

bool is_utf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t n = utf8_length(s, i);
    if (n == 0) return false;
    i += n;
  }
  return true;
}

std::string cpp_string_literal(const std::string& s) {
  std::string o = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_length(s, i);
    if (c == '"' || c == '\\' || c == '?') {
      o += '\\';
      o += static_cast<char>(c);
    } else if (n > 1 || (n == 1 && c >= 0x20 && c < 0x7F)) {
      o.append(s, i, n);
      i += n;
      continue;
    } else {
      // An octal escape has at most three digits: the next character cannot extend it.
      char b[8];
      std::snprintf(b, sizeof b, "\\%03o", c);
      o += b;
    }
    ++i;
  }
  return o + "\"";
}

std::string cpp_comment_text(const std::string& s) {
  std::string o;
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_length(s, i);
    if (c == '\\') {
      o += "\\\\";
    } else if (c == '\n') {
      o += "\\n";
    } else if (c == '/' && !o.empty() && o.back() == '*') {
      o += "\\/";  // `*/` would end a block comment
    } else if (c == '?' && !o.empty() && o.back() == '?') {
      o += "\\?";  // `??/` is a backslash where trigraphs are on
    } else if (n > 1 || (n == 1 && c >= 0x20 && c < 0x7F)) {
      o.append(s, i, n);
      i += n;
      continue;
    } else {
      o += hex_escape(c);
    }
    ++i;
  }
  if (!o.empty() && o.back() == '\\') o.replace(o.size() - 1, 1, "x5c");
  return o;
}

std::string json_string_literal(const std::string& s) {
  std::string o = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_length(s, i);
    switch (c) {
      case '"': o += "\\\""; break;
      case '\\': o += "\\\\"; break;
      case '\n': o += "\\n"; break;
      case '\t': o += "\\t"; break;
      case '\r': o += "\\r"; break;
      default:
        if (n == 0) {
          o += "\\ufffd";
        } else if (c < 0x20) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04x", c);
          o += b;
        } else {
          o.append(s, i, n);
          i += n;
          continue;
        }
    }
    ++i;
  }
  return o + "\"";
}

bool reserved_identifier(const std::string& id) {
  static const std::set<std::string> words = {
      "alignas", "alignof", "and", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "break",
      "case", "catch", "char", "char8_t", "char16_t", "char32_t", "class", "compl", "concept",
      "const", "consteval", "constexpr", "constinit", "const_cast", "continue", "co_await",
      "co_return", "co_yield", "decltype", "default", "delete", "do", "double", "dynamic_cast",
      "else", "enum", "explicit", "export", "extern", "false", "float", "for", "friend", "goto",
      "if", "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not", "not_eq",
      "nullptr", "operator", "or", "or_eq", "private", "protected", "public", "register",
      "reinterpret_cast", "requires", "return", "short", "signed", "sizeof", "static",
      "static_assert", "static_cast", "struct", "switch", "template", "this", "thread_local",
      "throw", "true", "try", "typedef", "typeid", "typename", "union", "unsigned", "using",
      "virtual", "void", "volatile", "wchar_t", "while", "xor", "xor_eq",
      // not keywords, but generated code cannot use them as names
      "std", "linux", "unix", "i386"};
  if (words.count(id)) return true;
  return id.size() > 1 && id[0] == '_' && (id[1] == '_' || (id[1] >= 'A' && id[1] <= 'Z'));
}

}  // namespace mbsgen
