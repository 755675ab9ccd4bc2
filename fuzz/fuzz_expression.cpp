// libFuzzer target: the expression parser (mbsgen::detail::parse_expression) against the symbol
// table of a small model (parameters m, k, l, g0; coordinates x, phi and their rates x_dot,
// phi_dot; an input u).
//
// The contract under test (yaml_reader.hpp): parsing either returns an expression or throws
// ExpressionError with an offset within the text. Any other exception escapes and aborts, an
// offset past the end of the text is reported with abort(), and a crash, a sanitizer report, a
// hang or runaway memory is a finding.
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

const mbsgen::Model& fuzz_model() {
  static const mbsgen::Model model = [] {
    mbsgen::Model m("fuzz");
    m.add_parameter("m", 1.5, "kg");
    m.add_parameter("k", 1000, "N/m");
    m.add_parameter("l", 0.25, "m");
    m.add_parameter("g0", 9.81, "m/s^2");
    m.add_coordinate("x", "m");
    m.add_coordinate("phi", "rad");
    m.add_input("u", "N");
    return m;
  }();
  return model;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const mbsgen::Model& model = fuzz_model();
  try {
    const GiNaC::ex e = mbsgen::detail::parse_expression(model, text);
    (void)e;
  } catch (const mbsgen::detail::ExpressionError& e) {
    // A rejected expression: the documented outcome; its offset points into the text (or just
    // past its end, for "unexpected end of expression").
    if (e.offset() > text.size()) {
      std::fprintf(stderr, "ExpressionError offset %zu past the end of a %zu-byte text: %s\n",
                   e.offset(), text.size(), e.what());
      std::abort();
    }
  }
  return 0;
}
