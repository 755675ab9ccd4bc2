// Adversarial input (issue 14 §3, §5; docs/testing.md "Adversarial input"): model strings are
// data, never code, and generated files are written all or nothing.
//
// HostileModels: every file of tests/data/hostile_models/ (its header says what it attacks) is
// generated, and then, independently of mbsgen's own escaping code:
// - the manifest is parsed by the strict JSON (RFC 8259) and UTF-8 checker below, and its
//   strings decode to the model's strings;
// - the generated .cpp files and a solver are compiled (-Werror=comment: a comment continued
//   onto the next line fails) and linked with the runtime; the solver prints every name and unit
//   it holds, byte for byte, which must be the model's bytes;
// - the solver draws a Bode plot with gnuplot; a command injected through a string would create
//   the file `canary`, which must not exist afterwards.
// OutputFiles, MbsgenCli: write_files, `mbsgen generate --id`, `mbsgen run`'s cache.
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/codegen/emit_api.hpp"
#include "mbsgen/generator/codegen/output_files.hpp"
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"
#include "mbsgen_build_config.hpp"
#include "run_process.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(MBSGEN_SOURCE_DIR) / "tests/data/hostile_models";

std::vector<std::string> words(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// ---- A strict JSON checker, written from RFC 8259 and RFC 3629, independent of emit.cpp. ----
class Json {
 public:
  explicit Json(const std::string& text) : s_(text) {}
  // Parses the whole text as one value; collects every string's decoded bytes.
  bool parse(std::string& error) {
    try {
      space();
      value();
      space();
      if (i_ != s_.size()) fail("text after the value");
      return true;
    } catch (const std::runtime_error& e) {
      error = e.what();
      return false;
    }
  }
  std::vector<std::string> strings;

 private:
  const std::string& s_;
  std::size_t i_ = 0;
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(what + " at offset " + std::to_string(i_));
  }
  int peek() const { return i_ < s_.size() ? static_cast<unsigned char>(s_[i_]) : -1; }
  void space() {
    while (peek() == ' ' || peek() == '\t' || peek() == '\n' || peek() == '\r') ++i_;
  }
  void expect(const char* word) {
    for (const char* p = word; *p; ++p, ++i_)
      if (peek() != *p) fail(std::string("expected ") + word);
  }
  void value() {
    const int c = peek();
    if (c == '{') return object();
    if (c == '[') return array();
    if (c == '"') return strings.push_back(string());
    if (c == 't') return expect("true");
    if (c == 'f') return expect("false");
    if (c == 'n') return expect("null");
    number();
  }
  void object() {
    ++i_;
    space();
    if (peek() == '}') return void(++i_);
    for (;;) {
      space();
      if (peek() != '"') fail("expected a key");
      strings.push_back(string());
      space();
      if (peek() != ':') fail("expected ':'");
      ++i_;
      space();
      value();
      space();
      if (peek() == '}') return void(++i_);
      if (peek() != ',') fail("expected ',' or '}'");
      ++i_;
    }
  }
  void array() {
    ++i_;
    space();
    if (peek() == ']') return void(++i_);
    for (;;) {
      space();
      value();
      space();
      if (peek() == ']') return void(++i_);
      if (peek() != ',') fail("expected ',' or ']'");
      ++i_;
    }
  }
  void number() {
    const std::size_t start = i_;
    if (peek() == '-') ++i_;
    if (peek() == '0') ++i_;
    else if (peek() >= '1' && peek() <= '9') while (peek() >= '0' && peek() <= '9') ++i_;
    else fail("expected a value");
    if (peek() == '.') {
      ++i_;
      if (!(peek() >= '0' && peek() <= '9')) fail("expected a digit");
      while (peek() >= '0' && peek() <= '9') ++i_;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++i_;
      if (peek() == '+' || peek() == '-') ++i_;
      if (!(peek() >= '0' && peek() <= '9')) fail("expected a digit");
      while (peek() >= '0' && peek() <= '9') ++i_;
    }
    if (i_ == start) fail("expected a number");
  }
  static void put(std::string& o, unsigned cp) {
    if (cp < 0x80) {
      o += static_cast<char>(cp);
    } else if (cp < 0x800) {
      o += static_cast<char>(0xC0 | (cp >> 6));
      o += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      o += static_cast<char>(0xE0 | (cp >> 12));
      o += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      o += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      o += static_cast<char>(0xF0 | (cp >> 18));
      o += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
      o += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      o += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }
  unsigned hex4() {
    unsigned v = 0;
    for (int k = 0; k < 4; ++k, ++i_) {
      const int c = peek();
      v *= 16;
      if (c >= '0' && c <= '9') v += c - '0';
      else if (c >= 'a' && c <= 'f') v += c - 'a' + 10;
      else if (c >= 'A' && c <= 'F') v += c - 'A' + 10;
      else fail("bad \\u escape");
    }
    return v;
  }
  // One UTF-8 character of the raw text (RFC 3629 section 4), appended to o.
  void utf8_char(std::string& o) {
    const unsigned c = static_cast<unsigned>(peek());
    unsigned n = 0, cp = 0, min = 0;
    if (c < 0x80) n = 1, cp = c;
    else if ((c & 0xE0) == 0xC0) n = 2, cp = c & 0x1F, min = 0x80;
    else if ((c & 0xF0) == 0xE0) n = 3, cp = c & 0x0F, min = 0x800;
    else if ((c & 0xF8) == 0xF0) n = 4, cp = c & 0x07, min = 0x10000;
    else fail("not UTF-8");
    for (unsigned k = 1; k < n; ++k) {
      const int b = i_ + k < s_.size() ? static_cast<unsigned char>(s_[i_ + k]) : -1;
      if (b < 0 || (b & 0xC0) != 0x80) fail("not UTF-8");
      cp = (cp << 6) | (static_cast<unsigned>(b) & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) fail("not UTF-8");
    o.append(s_, i_, n);
    i_ += n;
  }
  std::string string() {
    ++i_;
    std::string o;
    for (;;) {
      const int c = peek();
      if (c < 0) fail("unterminated string");
      if (c == '"') return ++i_, o;
      if (c < 0x20) fail("control character in a string");
      if (c != '\\') {
        utf8_char(o);
        continue;
      }
      ++i_;
      const int e = peek();
      ++i_;
      switch (e) {
        case '"': o += '"'; break;
        case '\\': o += '\\'; break;
        case '/': o += '/'; break;
        case 'b': o += '\b'; break;
        case 'f': o += '\f'; break;
        case 'n': o += '\n'; break;
        case 'r': o += '\r'; break;
        case 't': o += '\t'; break;
        case 'u': {
          unsigned cp = hex4();
          if (cp >= 0xD800 && cp <= 0xDBFF) {
            expect("\\u");
            const unsigned lo = hex4();
            if (lo < 0xDC00 || lo > 0xDFFF) fail("lone surrogate");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
          } else if (cp >= 0xDC00 && cp <= 0xDFFF) {
            fail("lone surrogate");
          }
          put(o, cp);
          break;
        }
        default: fail("bad escape");
      }
    }
  }
};

// RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF.
bool well_formed_utf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const unsigned c = static_cast<unsigned char>(s[i]);
    unsigned n = 0, cp = 0, min = 0;
    if (c < 0x80) n = 1, cp = c;
    else if ((c & 0xE0) == 0xC0) n = 2, cp = c & 0x1F, min = 0x80;
    else if ((c & 0xF0) == 0xE0) n = 3, cp = c & 0x0F, min = 0x800;
    else if ((c & 0xF8) == 0xF0) n = 4, cp = c & 0x07, min = 0x10000;
    else return false;
    if (i + n > s.size()) return false;
    for (unsigned k = 1; k < n; ++k) {
      const unsigned b = static_cast<unsigned char>(s[i + k]);
      if ((b & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (b & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += n;
  }
  return true;
}

std::string header_field(const std::string& text, const std::string& key) {
  const std::string tag = "# " + key + ": ";
  const auto at = text.find(tag);
  if (at == std::string::npos) return "";
  return text.substr(at + tag.size(), text.find('\n', at) - at - tag.size());
}

// The file the model is read from: the corpus file, or for file_name_newline.yaml a copy whose
// name holds a newline and a system() call.
fs::path model_path(const fs::path& corpus_file, const fs::path& dir) {
  if (corpus_file.stem() != "file_name_newline") return corpus_file;
  const fs::path copy = dir / "evil\n#include <cstdlib>\nstatic int canary = std::system(\"touch canary\");\n.yaml";
  fs::copy_file(corpus_file, copy);
  return copy;
}

std::string hex(const std::string& s) {
  std::string o;
  char b[4];
  for (unsigned char c : s) std::snprintf(b, sizeof b, "%02x", c), o += b;
  return o;
}

// The solver's main: `names` prints every name and unit in hex, anything else is the solver CLI.
std::string solver_main_source(const std::string& id) {
  return "#include \"" + id + "_model.hpp\"\n#include \"mbsgen/runtime/cli/solver_cli.hpp\"\n"
         "#include <cstdio>\n#include <cstring>\n"
         "static void dump(const char* what, const char* const* a, int n) {\n"
         "  for (int i = 0; i < n; ++i) {\n    std::printf(\"%s \", what);\n"
         "    for (const char* p = a[i]; *p; ++p) std::printf(\"%02x\", static_cast<unsigned char>(*p));\n"
         "    std::printf(\"\\n\");\n  }\n}\n"
         "int main(int argc, char** argv) {\n  const mbsgen::ModelKernels& k = " + id + "::kernels();\n"
         "  if (argc == 2 && std::strcmp(argv[1], \"names\") == 0) {\n"
         "    dump(\"coordinate\", k.coordinate_names, k.n_coordinates);\n"
         "    dump(\"coordinate_unit\", k.coordinate_units, k.n_coordinates);\n"
         "    dump(\"parameter\", k.parameter_names, k.n_parameters);\n"
         "    dump(\"parameter_unit\", k.parameter_units, k.n_parameters);\n"
         "    dump(\"input\", k.input_names, k.n_inputs);\n    dump(\"input_unit\", k.input_units, k.n_inputs);\n"
         "    dump(\"output\", k.output_names, k.n_outputs);\n    dump(\"output_unit\", k.output_units, k.n_outputs);\n"
         "    return 0;\n  }\n  return mbsgen::cli::solver_main(k, argc, argv);\n}\n";
}

std::string expected_names(const mbsgen::Model& m) {
  std::string o;
  for (const auto& c : m.coordinates()) o += "coordinate " + hex(c.name) + "\n";
  for (const auto& c : m.coordinates()) o += "coordinate_unit " + hex(c.unit) + "\n";
  for (const auto& p : m.parameters()) o += "parameter " + hex(p.name) + "\n";
  for (const auto& p : m.parameters()) o += "parameter_unit " + hex(p.unit) + "\n";
  for (const auto& i : m.inputs()) o += "input " + hex(i.name) + "\n";
  for (const auto& i : m.inputs()) o += "input_unit " + hex(i.unit) + "\n";
  for (const auto& z : m.outputs()) o += "output " + hex(z.name) + "\n";
  for (const auto& z : m.outputs()) o += "output_unit " + hex(z.unit) + "\n";
  return o;
}

struct Generated {
  std::string id;
  mbsgen::Model model{""};
};

Generated generate(const fs::path& file, const std::string& scene, const fs::path& out) {
  const mbsgen::Model full = mbsgen::read_model_file(file.string());
  Generated g{"", mbsgen::apply_scene(full, scene)};
  mbsgen::Equations eq = mbsgen::derive(g.model);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  mbsgen::check_operating_point(eq, lin);
  mbsgen::EmitOptions options;
  options.source_file = file.string();
  mbsgen::GeneratedCode code = mbsgen::emit(g.model, eq, lin, options);
  const auto& range = g.model.selection().frequency_range;
  mbsgen::write_generated(code, mbsgen::emit_api(g.model, lin, code, scene, range ? range->from_hz : 0.0,
                                                 range ? range->to_hz : 0.0),
                          out.string());
  g.id = code.id;
  return g;
}

// The manifest parses, and its strings include the model's (those that are UTF-8; a string
// that is not must come out as well-formed UTF-8, which parse() checks).
void check_manifest(const fs::path& json, const mbsgen::Model& model) {
  const std::string text = slurp(json);
  Json j(text);
  std::string error;
  ASSERT_TRUE(j.parse(error)) << json << ": " << error;
  auto has = [&](const std::string& s) {
    return std::find(j.strings.begin(), j.strings.end(), s) != j.strings.end();
  };
  std::vector<std::string> strings = {model.name(), model.selection().description};
  for (const auto& p : model.parameters()) strings.insert(strings.end(), {p.unit, p.source});
  for (const auto& z : model.outputs()) strings.insert(strings.end(), {z.name, z.unit});
  for (const auto& i : model.inputs()) strings.push_back(i.unit);
  for (const auto& b : model.bodies()) strings.push_back(b.name);
  for (const auto& s : strings)
    if (well_formed_utf8(s)) {
      EXPECT_TRUE(has(s)) << json << " lacks the string " << hex(s);
    }
}

class HostileModels : public ::testing::TestWithParam<std::string> {};

TEST_P(HostileModels, OutputsAreSafe) {
  const fs::path file = kCorpus / GetParam();
  const std::string text = slurp(file);
  ASSERT_FALSE(header_field(text, "attack").empty()) << file << ": no '# attack:' line";
  // `# expect: refused: LINE:COL: error: MESSAGE`: the reader refuses the model (a model named
  // after a C++ keyword, issue 14 §3), with exactly that message.
  if (const std::string refused = "refused: "; header_field(text, "expect").rfind(refused, 0) == 0) {
    try {
      mbsgen::read_model_file(file.string());
      ADD_FAILURE() << file << ": not refused";
    } catch (const mbsgen::ModelError& e) {
      EXPECT_EQ(e.what(), file.string() + ":" + header_field(text, "expect").substr(refused.size()));
    }
    return;
  }
  ASSERT_EQ(header_field(text, "expect").rfind("generated", 0), 0u) << file;
  const fs::path dir = temporary_directory();
  const fs::path path = model_path(file, dir), out = dir / "out";
  Generated full = generate(path, "full", out);
  const std::string want_id = header_field(text, "id");
  EXPECT_EQ(full.id, want_id.empty() ? full.model.name() : want_id);
  check_manifest(out / (full.id + ".json"), full.model);
  Generated sweep = generate(path, "sweep", out);
  check_manifest(out / (sweep.id + ".json"), sweep.model);

  // Compile the kernels, the typed API and a solver (GNU mode: `linux` is a macro there).
  std::ofstream(out / "main.cpp") << solver_main_source(full.id);
  std::vector<std::string> cc = {MBSGEN_CXX_COMPILER, "-std=gnu++17", "-O0", "-Wall", "-Werror=comment",
                                 "-I" + out.string(), std::string("-I") + MBSGEN_BUILD_RUNTIME_INCLUDE};
  for (auto& w : words(MBSGEN_EXTRA_INCLUDES)) cc.push_back(w);
  for (const std::string& f : {full.id + ".cpp", full.id + "_model.cpp", std::string("main.cpp")})
    cc.push_back((out / f).string());
  cc.insert(cc.end(), {"-o", (dir / "solve").string(), MBSGEN_BUILD_SOLVER_LIBRARY, MBSGEN_BUILD_RUNTIME_LIBRARY});
  for (auto& w : words(MBSGEN_EXTRA_LIBRARIES)) cc.push_back(w);
  const Result compiled = run(cc, dir);
  ASSERT_EQ(compiled.status, 0) << compiled.output;
  EXPECT_EQ(compiled.output.find("warning"), std::string::npos) << compiled.output;
  // The scene's files compile too (syntax only: the same strings, another id).
  const Result scene = run({MBSGEN_CXX_COMPILER, "-std=gnu++17", "-fsyntax-only", "-Werror=comment",
                            "-I" + out.string(), (out / (sweep.id + ".cpp")).string()},
                           dir);
  EXPECT_EQ(scene.status, 0) << scene.output;

  // The solver holds exactly the model's bytes.
  const Result names = run({(dir / "solve").string(), "names"}, dir);
  ASSERT_EQ(names.status, 0) << names.output;
  EXPECT_EQ(names.output, expected_names(full.model));

  // A Bode plot through gnuplot with every label of the model; nothing may run.
  const Result plot = run({(dir / "solve").string(), "frf", "--input", full.model.inputs()[0].name, "--output",
                           full.model.outputs()[0].name, "--points", "5", "--plot", "bode.svg"},
                          dir);
  EXPECT_EQ(plot.status, 0) << plot.output;
  EXPECT_GT(fs::exists(dir / "bode.svg") ? fs::file_size(dir / "bode.svg") : 0u, 1000u) << plot.output;
  EXPECT_FALSE(fs::exists(dir / "canary")) << "a command injected through the model ran";
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
  fs::remove_all(dir);
}

std::vector<std::string> corpus() {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(kCorpus))
    if (e.path().extension() == ".yaml") files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

INSTANTIATE_TEST_SUITE_P(Corpus, HostileModels, ::testing::ValuesIn(corpus()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           return fs::path(param.param).stem().string();
                         });

TEST(HostileModels, CorpusHasEveryKind) { EXPECT_GE(corpus().size(), 15u); }

// ---- write_files: all or nothing ----

std::vector<mbsgen::OutputFile> three_files(const fs::path& dir, std::size_t big) {
  return {{dir / "a.hpp", "// Generated by mbsgen: a\n"},
          {dir / "b.cpp", "// Generated by mbsgen: b\n" + std::string(big, 'x') + "\n"},
          {dir / "c.json", "{\"generator\": \"mbsgen\"}\n"}};
}

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> v;
  for (const auto& e : fs::directory_iterator(dir)) v.push_back(e.path().filename().string());
  std::sort(v.begin(), v.end());
  return v;
}

TEST(OutputFiles, AUsersFileStopsEveryWrite) {
  const fs::path dir = temporary_directory();
  std::ofstream(dir / "b.cpp") << "int mine() { return 1; }\n";
  try {
    mbsgen::write_files(three_files(dir, 10));
    ADD_FAILURE() << "overwrote a user's file";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "refusing to overwrite " + (dir / "b.cpp").string() +
                                         ": it exists and was not written by mbsgen (move it, or "
                                         "choose another --out or --id)");
  }
  // a.hpp comes first, but nothing was written.
  EXPECT_EQ(listing(dir), std::vector<std::string>{"b.cpp"});
  EXPECT_EQ(slurp(dir / "b.cpp"), "int mine() { return 1; }\n");
  fs::remove_all(dir);
}

TEST(OutputFiles, AFifoIsRefusedWithoutBlocking) {
  const fs::path dir = temporary_directory();
  ASSERT_EQ(::mkfifo((dir / "c.json").c_str(), 0600), 0);
  try {
    mbsgen::write_files(three_files(dir, 10));
    ADD_FAILURE() << "wrote over a FIFO";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "refusing to overwrite " + (dir / "c.json").string() + ": it is a FIFO, not a file mbsgen wrote");
  }
  EXPECT_EQ(listing(dir), std::vector<std::string>{"c.json"});
  fs::remove_all(dir);
}

// A write that fails midway (here the file size limit, as a full disk would) leaves the old
// files as they were and no temporary file. Run in a child: the limit is per process.
TEST(OutputFiles, AFailedWriteLeavesNothing) {
  const fs::path dir = temporary_directory();
  std::ofstream(dir / "a.hpp") << "// Generated by mbsgen: old a\n";
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    std::signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG instead of killing
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    std::string message = "no error";
    try {
      mbsgen::write_files(three_files(dir, 10000));
    } catch (const std::exception& e) {
      message = e.what();
    }
    if (::write(fds[1], message.data(), message.size()) < 0) ::_exit(2);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string message;
  char buf[512];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) message.append(buf, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_EQ(message, "cannot write " + (dir / "b.cpp").string() + ": File too large (nothing was written)");
  EXPECT_EQ(listing(dir), std::vector<std::string>{"a.hpp"});
  EXPECT_EQ(slurp(dir / "a.hpp"), "// Generated by mbsgen: old a\n");
  fs::remove_all(dir);
}

// ---- The mbsgen command ----

TEST(MbsgenCli, IdThatIsAKeywordIsAUsageError) {
  const fs::path dir = temporary_directory();
  const std::string model = (kCorpus / "unit_backquote.yaml").string();
  for (const std::string id : {"int", "std", "linux", "_Reserved", "__x"}) {
    const Result r = run({MBSGEN_TOOL, "generate", model, "--id", id, "--out", "out"}, dir);
    EXPECT_EQ(r.status, 2) << id;
    EXPECT_EQ(r.output, "mbsgen generate: --id '" + id +
                            "' is a C++ keyword or a name C++ reserves (such as int, std, linux, _X, "
                            "__x): the generated code could not use it\n");
  }
  const Result r = run({MBSGEN_TOOL, "generate", model, "--id", "a b", "--out", "out"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.output, "mbsgen generate: --id 'a b' is not a C identifier (letters, digits and _, not "
                      "starting with a digit)\n");
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

// --dynamics adds the dynamics kernel (EmitOptions::dynamics) to the header and the manifest;
// without it there is none (kernel_parts_test.cpp checks its values).
TEST(MbsgenCli, DynamicsFlagAddsTheDynamicsKernel) {
  const fs::path dir = temporary_directory();
  const std::string model = (kCorpus / "unit_backquote.yaml").string();
  Result r = run({MBSGEN_TOOL, "generate", model, "--id", "plain", "--out", "a"}, dir);
  ASSERT_EQ(r.status, 0) << r.output;
  r = run({MBSGEN_TOOL, "generate", model, "--id", "both", "--out", "b", "--dynamics"}, dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(slurp(dir / "a" / "plain.hpp").find("_dynamics("), std::string::npos);
  EXPECT_NE(slurp(dir / "b" / "both.hpp").find("int both_dynamics(const double* y, const double* yd, const double* u, "
                                                "const double* p, double* M, double* r);"),
            std::string::npos);
  EXPECT_NE(slurp(dir / "b" / "both.json").find("\"name\": \"dynamics\""), std::string::npos);
  // Refused, writing nothing: a nonholonomic model (no second-order form) and a scene (pruned).
  const fs::path models = fs::path(MBSGEN_SOURCE_DIR) / "models";
  r = run({MBSGEN_TOOL, "generate", (models / "rolling/rolling_disk.yaml").string(), "--out", "c", "--dynamics"}, dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("needs the second-order form"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "c"));
  r = run({MBSGEN_TOOL, "generate", (models / "textbook/chain3_sympy.yaml").string(), "--scene", "no_damping", "--out",
           "d", "--dynamics"},
          dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("scene 'no_damping' does not (add simulate to its analyses"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "d"));
  fs::remove_all(dir);
}

// The full model's sensitivity kernel exists only when asked (issue 40 §2): --sensitivity (every
// parameter), --sensitivity-parameters (those; an unknown one refused), and `mbsgen run … --
// modes --sensitivity NAMES`, which builds its own cached solver with the kernel by NAMES:
// dλ/dk of m ẍ + c ẋ + k x = 0 is −1/(2 m λ + c) = i/(2 ω_d) at λ = −c/2m + i ω_d (m = 1,
// k = 100, c = 0.5: ω_d = 9.99687 rad/s, dλ/dk = 0.0500156 i), and (k/f_n) df_n/dk = 1/2.
TEST(MbsgenCli, SensitivityIsMadeWhenAsked) {
  const fs::path dir = temporary_directory();
  const std::string model = (kCorpus / "unit_backquote.yaml").string();
  Result r = run({MBSGEN_TOOL, "generate", model, "--id", "plain", "--out", "a"}, dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(slurp(dir / "a" / "plain.hpp").find("_sensitivity("), std::string::npos);
  r = run({MBSGEN_TOOL, "generate", model, "--id", "all", "--out", "b", "--sensitivity"}, dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(slurp(dir / "b" / "all.hpp").find("all_n_sensitivity_parameters = 3"), std::string::npos);
  r = run({MBSGEN_TOOL, "generate", model, "--id", "some", "--out", "c", "--sensitivity-parameters", "k,m"}, dir);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(slurp(dir / "c" / "some.hpp").find("some_n_sensitivity_parameters = 2"), std::string::npos);
  EXPECT_NE(slurp(dir / "c" / "some.cpp").find("some_sensitivity_parameter_names[] = {\"m\", \"k\", nullptr}"),
            std::string::npos);
  r = run({MBSGEN_TOOL, "generate", model, "--out", "d", "--sensitivity-parameters", "kk"}, dir);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("sensitivity: model 'oscillator' has no parameter 'kk'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "d"));
  const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", (dir / "cache").string()}};
  r = run({MBSGEN_TOOL, "run", model, "--", "modes", "--sensitivity", "kk"}, dir, env);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.output.find("mbsgen run: modes --sensitivity: model 'oscillator' has no parameter 'kk'"),
            std::string::npos)
      << r.output;
  r = run({MBSGEN_TOOL, "run", model, "--", "modes", "--sensitivity", "k", "--format", "csv"}, dir, env);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(",\"k\",100,-0,0.0500156323"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(",0.5000000000000"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

// `mbsgen run`: a Bode plot of a model with backquotes in its units runs nothing; a truncated or
// deleted cached solver is noticed and rebuilt (it used to crash on every run).
// A damaged cache entry is reported and rebuilt: a compiled solver (--compiled) and a tape.
TEST(MbsgenCli, RunRebuildsADamagedCacheEntry) {
  for (const std::string artifact : {"solve", "tape"}) {
    SCOPED_TRACE(artifact);
    const std::string noun = artifact == "solve" ? "solver" : "tape";
    const fs::path dir = temporary_directory();
    const std::map<std::string, std::string> env = {{"MBSGEN_CACHE_DIR", (dir / "cache").string()}};
    std::vector<std::string> frf = {MBSGEN_TOOL, "run", (kCorpus / "unit_backquote.yaml").string(), "--",
                                    "frf", "--input", "F", "--output", "position", "--points", "5",
                                    "--plot", "bode.png"};
    if (artifact == "solve") frf.insert(frf.begin() + 3, "--compiled");
    Result r = run(frf, dir, env);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir / "bode.png"));
    EXPECT_FALSE(fs::exists(dir / "canary"));
    std::vector<fs::path> entries;
    for (const auto& e : fs::directory_iterator(dir / "cache")) entries.push_back(e.path());
    ASSERT_EQ(entries.size(), 1u);
    const fs::path file = entries[0] / artifact;
    fs::resize_file(file, 4096);
    r = run(frf, dir, env);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("mbsgen run: the cached " + noun + " " + entries[0].string() + " is damaged (the " + noun +
                            " does not match its record): rebuilding it"),
              std::string::npos)
        << r.output;
    fs::remove(file);
    r = run(frf, dir, env);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("is damaged (the " + noun + " is missing): rebuilding it"), std::string::npos) << r.output;
    r = run(frf, dir, env);  // sound again: no message
    EXPECT_EQ(r.status, 0);
    EXPECT_EQ(r.output.find("damaged"), std::string::npos) << r.output;
    // One byte changed in place, the size kept: the time changed, so the file is read whole
    // (a run that finds inode, size and time as recorded does not read it; issue 45).
    {
      std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
      const auto middle = static_cast<std::streamoff>(fs::file_size(file) / 2);
      f.seekg(middle);
      const char c = static_cast<char>(f.get());
      f.seekp(middle);
      f.put(static_cast<char>(c ^ 0x5a));
    }
    r = run(frf, dir, env);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("is damaged (the " + noun + " does not match its record): rebuilding it"), std::string::npos)
        << r.output;
    // Touched but intact (as a copy is): sound, no message, and stamped anew.
    const std::string record = slurp(file.string() + ".sum");
    const timespec old_times[2] = {{1000000000, 0}, {1000000000, 0}};
    ASSERT_EQ(::utimensat(AT_FDCWD, file.c_str(), old_times, 0), 0);
    r = run(frf, dir, env);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output.find("damaged"), std::string::npos) << r.output;
    const std::string restamped = slurp(file.string() + ".sum");
    EXPECT_NE(restamped, record);
    EXPECT_EQ(restamped.substr(0, restamped.find(" inode")), record.substr(0, record.find(" inode")));
    EXPECT_FALSE(fs::exists(dir / "canary"));
    fs::remove_all(dir);
  }
}

// The processes whose command line names `path` (the compilers a build in a cache runs).
std::vector<pid_t> processes_naming(const std::string& path) {
  std::vector<pid_t> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = slurp(e.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find(path) != std::string::npos) found.push_back(static_cast<pid_t>(std::stol(name)));
  }
  return found;
}

// `mbsgen run` stopped by SIGTERM while it compiles (the middle ear: seconds of compiling) stops
// its compilers, the drivers' cc1plus included, and leaves no half-built directory in the cache;
// it exits with 128 + 15. They used to run on, orphaned, writing into the cache.
TEST(MbsgenCli, RunStoppedStopsItsCompilers) {
  const fs::path dir = temporary_directory();
  const fs::path cache = dir / "cache";
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    FILE* f = std::freopen((dir / "output").c_str(), "w", stdout);
    if (!f || ::dup2(STDOUT_FILENO, STDERR_FILENO) < 0) ::_exit(126);
    ::setenv("MBSGEN_CACHE_DIR", cache.c_str(), 1);
    const std::string model = std::string(MBSGEN_SOURCE_DIR) + "/models/middle_ear/middle_ear.yaml";
    ::execl(MBSGEN_TOOL, MBSGEN_TOOL, "run", model.c_str(), "--compiled", "--", "modes", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_GT(pid, 0);
  bool compiling = false;
  int status = 0;
  for (int i = 0; i < 3000 && !compiling; ++i) {  // at most 300 s (a sanitizer build derives slowly)
    if (::waitpid(pid, &status, WNOHANG) == pid) break;
    compiling = !processes_naming(cache.string()).empty();
    if (!compiling) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_TRUE(compiling) << "no compiler seen; " << slurp(dir / "output");
  ::kill(pid, SIGTERM);
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM) << slurp(dir / "output");
  EXPECT_NE(slurp(dir / "output").find("mbsgen run: stopped by signal 15; the solver was not built"),
            std::string::npos);
  std::vector<pid_t> left = processes_naming(cache.string());
  for (int i = 0; i < 100 && !left.empty(); ++i) {  // they end within moments of SIGTERM
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    left = processes_naming(cache.string());
  }
  EXPECT_TRUE(left.empty()) << left.size() << " compiler processes still running";
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(cache)) entries += e.path().empty() ? 0 : 1;
  EXPECT_EQ(entries, 0u) << "a half-built directory was left in the cache";
  fs::remove_all(dir);
}

}  // namespace
