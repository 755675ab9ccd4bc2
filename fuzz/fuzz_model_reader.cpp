// libFuzzer target: the YAML model reader (mbsgen::read_model_string) on arbitrary bytes.
//
// The contract under test (yaml_reader.hpp): reading either returns a validated Model or throws
// ModelError. Any other exception escapes this function and aborts (std::terminate), and so does
// a crash, a sanitizer report, a hang (-timeout) or runaway memory (-rss_limit_mb): each is a
// finding. Built as a libFuzzer binary with clang (MBSGEN_BUILD_FUZZ) and, with any compiler,
// linked into the smoke driver of the test suite (smoke_driver.cpp).
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const mbsgen::Model model = mbsgen::read_model_string(text, "fuzz.yaml");
    (void)model;
  } catch (const mbsgen::ModelError&) {
    // A rejected model: the documented outcome for bad input.
  }
  return 0;
}
