// Strings of a model (names, units, sources, descriptions, its file name) as data in the
// languages mbsgen writes: C++ string literals and comments, JSON strings, C++ identifiers.
// Whatever the string holds (newlines, backslashes, quotes, `*/`, bytes that are not UTF-8),
// the result is one token of that language that says the string and nothing else.
#pragma once

#include <string>

namespace mbsgen {

/// Whether s is well-formed UTF-8 (no overlong forms, surrogates or code points above U+10FFFF).
bool is_utf8(const std::string& s);

/// A C++ string literal with the bytes of s: printable ASCII and well-formed UTF-8 as they are,
/// `"` `\` `?` escaped, every other byte (controls, DEL, bytes that are not UTF-8) as a 3-digit
/// octal escape, so the literal holds exactly s.
std::string cpp_string_literal(const std::string& s);

/// s as text inside a C++ `//` or `/* */` comment, on one line: `\` doubled, newlines, other
/// controls, DEL and bytes that are not UTF-8 as `\n`, `\xNN`; `*/` and `??` broken by a
/// backslash. The result never ends with a backslash (a final one is written `\x5c`), so it
/// cannot continue the comment onto the next line.
std::string cpp_comment_text(const std::string& s);

/// A JSON string (RFC 8259) for s: `"` `\` and controls escaped; a byte that is not part of
/// well-formed UTF-8 becomes U+FFFD (JSON text is UTF-8, and cannot hold other bytes).
std::string json_string_literal(const std::string& s);

/// Whether id, a C++ identifier, may not name generated C++ entities: a C++ keyword or
/// alternative token (C++20 included), `std`, a macro predefined by GCC in GNU modes (`linux`,
/// `unix`, `i386`), or a name reserved to the implementation (`_` and a capital, or `__`, first).
bool reserved_identifier(const std::string& id);

}  // namespace mbsgen
