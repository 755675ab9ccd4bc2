// Tests of the YAML model reader: every textbook model reads and validates; every bad model in
// tests/data/bad_models fails with exactly the message its first line announces; decimal
// literals are exact; defaults and conversions do what docs/model-format.md says. A bad model
// may also fail later, at the numerical checks of its operating point that `mbsgen check` runs
// (operating_point_check.hpp): singular mass matrix, an operating point that is not an equilibrium.
#include "mbsgen/generator/linear/operating_point_check.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

using mbsgen::ModelError;
namespace fs = std::filesystem;

const std::string kSourceDir = MBSGEN_SOURCE_DIR;

// Returns the message of the ModelError that reading `path` throws, or "" when none is thrown.
std::string error_of_file(const std::string& path) {
  try {
    const mbsgen::Model model = mbsgen::read_model_file(path);
    mbsgen::Equations eq = mbsgen::derive(model);
    mbsgen::check_operating_point(eq, mbsgen::linearize(eq));
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

std::string error_of_string(const std::string& text) {
  try {
    mbsgen::read_model_string(text, "test.yaml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

bool same(const GiNaC::ex& a, const GiNaC::ex& b) { return (a - b).expand().is_zero(); }

// ---------------------------------------------------------------------------------------------
// Textbook models

struct TextbookCase {
  const char* file;
  std::size_t coordinates;
  std::size_t bodies;
};

class TextbookModel : public testing::TestWithParam<TextbookCase> {};

TEST_P(TextbookModel, ReadsAndValidates) {
  const TextbookCase c = GetParam();
  const std::string path = kSourceDir + "/models/textbook/" + c.file;
  ASSERT_TRUE(fs::exists(path)) << path;
  try {
    const mbsgen::Model model = mbsgen::read_model_file(path);
    EXPECT_EQ(model.coordinates().size(), c.coordinates);
    EXPECT_EQ(model.bodies().size(), c.bodies);
    EXPECT_NO_THROW(model.validate());
  } catch (const ModelError& e) {
    FAIL() << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, TextbookModel,
    testing::Values(TextbookCase{"simple_pendulum.yaml", 1, 1},
                    TextbookCase{"physical_pendulum.yaml", 1, 1},
                    TextbookCase{"double_pendulum.yaml", 2, 2},
                    TextbookCase{"double_pendulum_rods.yaml", 2, 2},
                    TextbookCase{"spring_chain_fixed_fixed.yaml", 5, 5},
                    TextbookCase{"spring_chain_fixed_free.yaml", 5, 5},
                    TextbookCase{"spring_chain_free_free.yaml", 5, 5},
                    TextbookCase{"spherical_pendulum_conical.yaml", 2, 1},
                    TextbookCase{"rotor_disk.yaml", 3, 2},
                    TextbookCase{"jeffcott_rotor.yaml", 2, 1},
                    TextbookCase{"sleeping_top.yaml", 3, 1},
                    TextbookCase{"heavy_top_precession.yaml", 3, 1},
                    TextbookCase{"ziegler_column.yaml", 2, 2},
                    TextbookCase{"chain3_sympy.yaml", 3, 3},
                    TextbookCase{"base_excited_oscillator.yaml", 1, 2},
                    TextbookCase{"shaken_pendulum.yaml", 1, 2},
                    TextbookCase{"torqued_pendulum.yaml", 1, 1}),
    [](const testing::TestParamInfo<TextbookCase>& param_info) {
      std::string name = param_info.param.file;
      return name.substr(0, name.find('.'));
    });

TEST(TextbookModels, EveryFileIsListed) {
  std::size_t n = 0;
  for (const auto& entry : fs::directory_iterator(kSourceDir + "/models/textbook"))
    if (entry.path().extension() == ".yaml") ++n;
  EXPECT_EQ(n, 17u) << "a model file was added or removed: update the list of TextbookModel";
}

TEST(DoublePendulum, ContentsAsWritten) {
  const mbsgen::Model m = mbsgen::read_model_file(kSourceDir + "/models/textbook/double_pendulum.yaml");
  EXPECT_EQ(m.name(), "double_pendulum");
  ASSERT_EQ(m.parameters().size(), 5u);
  EXPECT_EQ(m.parameters()[4].name, "g");
  EXPECT_EQ(m.parameters()[4].value, 9.81);
  EXPECT_EQ(m.parameters()[4].unit, "m/s^2");
  EXPECT_EQ(m.parameters()[0].source, "closed-forms.md §2, equal masses");
  ASSERT_EQ(m.coordinates().size(), 2u);
  EXPECT_EQ(m.coordinates()[1].name, "phi2");
  EXPECT_EQ(m.coordinates()[1].unit, "rad");
  ASSERT_EQ(m.bodies().size(), 2u);
  const mbsgen::Body& rod2 = m.bodies()[1];
  EXPECT_EQ(rod2.parent, "rod1");
  ASSERT_EQ(rod2.rotations.size(), 1u);
  EXPECT_EQ(rod2.rotations[0].axis, mbsgen::Axis::z);
  EXPECT_TRUE(same(rod2.rotations[0].angle, m.symbol("phi2") - m.symbol("phi1")));
  EXPECT_TRUE(same(rod2.translation[1], -m.symbol("l1")));
  EXPECT_TRUE(same(rod2.com[1], -m.symbol("l2")));
  EXPECT_TRUE(same(rod2.mass, m.symbol("m2")));
  EXPECT_EQ(m.marker("tip").body, "rod2");
  EXPECT_EQ(m.marker("pivot").body, mbsgen::kWorld);
  ASSERT_EQ(m.gravity().size(), 1u);
  EXPECT_EQ(m.gravity()[0].name, "gravity1");
  EXPECT_TRUE(same(m.gravity()[0].g[1], -m.symbol("g")));
  ASSERT_EQ(m.applied_forces().size(), 1u);
  EXPECT_EQ(m.applied_forces()[0].frame, mbsgen::ForceFrame::world);
  EXPECT_TRUE(same(m.applied_forces()[0].force[0], m.symbol("F")));
  ASSERT_EQ(m.outputs().size(), 4u);
  EXPECT_EQ(m.outputs()[0].kind, mbsgen::OutputKind::position);
  EXPECT_EQ(m.outputs()[1].kind, mbsgen::OutputKind::velocity);
  EXPECT_EQ(m.outputs()[2].kind, mbsgen::OutputKind::coordinate);
  EXPECT_EQ(m.outputs()[3].kind, mbsgen::OutputKind::expression);
  EXPECT_EQ(m.operating_point().kind, mbsgen::LinearizationPoint::Kind::given);
  // The body's location is the start of its map in the file.
  EXPECT_EQ(rod2.where.line, 35);
  EXPECT_EQ(rod2.where.column, 5);
}

TEST(SphericalPendulum, OperatingPointIsAnExactExpression) {
  const mbsgen::Model m =
      mbsgen::read_model_file(kSourceDir + "/models/textbook/spherical_pendulum_conical.yaml");
  const auto& op = m.operating_point();
  EXPECT_TRUE(same(op.position.at("theta"), GiNaC::Pi / 6));
  const GiNaC::ex rate = op.velocity.at("phi");
  const GiNaC::ex value = GiNaC::evalf(rate.subs(GiNaC::lst{m.symbol("g") == GiNaC::numeric(981, 100),
                                                           m.symbol("L") == 1}));
  ASSERT_TRUE(GiNaC::is_a<GiNaC::numeric>(value));
  // docs/test-references.md §5: phi'0 = 3.36565183604907 rad/s (15 digits given there).
  EXPECT_NEAR(GiNaC::ex_to<GiNaC::numeric>(value).to_double(), 3.36565183604907, 1e-14);
}

TEST(ChainSympy, DecimalValuesAreExactInExpressionsAndRoundedAsParameters) {
  const mbsgen::Model m = mbsgen::read_model_file(kSourceDir + "/models/textbook/chain3_sympy.yaml");
  EXPECT_EQ(m.parameters()[1].value, 1.5);
  EXPECT_EQ(m.parameters()[9].name, "c1");
  EXPECT_EQ(m.parameters()[9].value, 0.1);  // the double nearest to 1/10
  ASSERT_EQ(m.generalized_forces().size(), 6u);
  EXPECT_TRUE(same(m.generalized_forces()[0].value, -m.symbol("k1") * m.symbol("q1")));
  EXPECT_EQ(m.generalized_forces()[0].category, mbsgen::Category::springs);
  EXPECT_TRUE(same(m.generalized_forces()[3].value, -m.symbol("c1") * m.symbol("q1_dot")));
  EXPECT_EQ(m.generalized_forces()[3].category, mbsgen::Category::dampers);
}

TEST(Scenes, ReadAsWritten) {
  const mbsgen::Model m = mbsgen::read_model_file(kSourceDir + "/models/textbook/rotor_disk.yaml");
  ASSERT_EQ(m.scenes().size(), 3u);
  EXPECT_EQ(m.scenes()[2].analyses, std::vector<mbsgen::Analysis>{mbsgen::Analysis::simulate});
  const mbsgen::Scene& rest = m.scenes()[0];
  EXPECT_EQ(rest.name, "modes_at_rest");
  EXPECT_EQ(rest.description, "natural frequencies of the disk at standstill");
  ASSERT_EQ(rest.analyses.size(), 1u);
  EXPECT_EQ(rest.analyses[0], mbsgen::Analysis::modes);
  EXPECT_FALSE(rest.effects.has_value());
  EXPECT_TRUE(rest.without.empty());
  EXPECT_FALSE(rest.inputs.has_value());
  EXPECT_TRUE(rest.operating_point.position.empty());
  EXPECT_FALSE(rest.operating_point.kind.has_value());
  ASSERT_EQ(rest.operating_point.velocity.count("gamma"), 1u);
  EXPECT_TRUE(rest.operating_point.velocity.at("gamma").is_zero());
  EXPECT_FALSE(rest.frequency_range.has_value());
  const mbsgen::Scene& spin = m.scenes()[1];
  EXPECT_EQ(spin.name, "spinning");
  ASSERT_EQ(spin.analyses.size(), 2u);
  EXPECT_EQ(spin.analyses[1], mbsgen::Analysis::frf);
  ASSERT_TRUE(spin.inputs.has_value());
  ASSERT_EQ(spin.inputs->size(), 1u);
  EXPECT_EQ((*spin.inputs)[0].name, "T");
  EXPECT_GT((*spin.inputs)[0].where.line, 0);
  ASSERT_TRUE(spin.outputs.has_value());
  EXPECT_EQ((*spin.outputs)[0].name, "tilt_x");
  ASSERT_TRUE(spin.frequency_range.has_value());
  EXPECT_EQ(spin.frequency_range->from_hz, 1.0);
  EXPECT_EQ(spin.frequency_range->to_hz, 100.0);
  EXPECT_EQ(spin.frequency_range->points, 400);
  EXPECT_TRUE(spin.frequency_range->logarithmic);
}

// ---------------------------------------------------------------------------------------------
// Bad models: the first line of each file is `# expect: LINE:COL: error: MESSAGE`, where
// `{file}` stands for the file's path.

std::vector<std::string> bad_model_files() {
  std::vector<std::string> files;
  const fs::path dir = fs::path(kSourceDir) / "tests" / "data" / "bad_models";
  if (fs::exists(dir))
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.path().extension() == ".yaml") files.push_back(entry.path().filename().string());
  std::sort(files.begin(), files.end());
  return files;
}

class BadModel : public testing::TestWithParam<std::string> {};

TEST_P(BadModel, FailsWithTheAnnouncedMessage) {
  const std::string path = kSourceDir + "/tests/data/bad_models/" + GetParam();
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  const std::string prefix = "# expect: ";
  ASSERT_EQ(first.rfind(prefix, 0), 0u) << path << ": the first line must be '" << prefix << "…'";
  std::string expected = first.substr(prefix.size());
  for (std::size_t at; (at = expected.find("{file}")) != std::string::npos;)
    expected.replace(at, 6, path);
  EXPECT_EQ(error_of_file(path), path + ":" + expected);
}

INSTANTIATE_TEST_SUITE_P(Files, BadModel, testing::ValuesIn(bad_model_files()),
                         [](const testing::TestParamInfo<std::string>& param_info) {
                           return param_info.param.substr(0, param_info.param.find('.'));
                         });

TEST(BadModels, AreThere) { EXPECT_GE(bad_model_files().size(), 30u); }

// ---------------------------------------------------------------------------------------------
// Expressions

class Expressions : public testing::Test {
 protected:
  Expressions() : model("m") {
    model.add_parameter("l", 1.0);
    model.add_coordinate("phi");
  }
  GiNaC::ex parse(const std::string& text) { return mbsgen::detail::parse_expression(model, text); }
  mbsgen::Model model;
};

TEST_F(Expressions, DecimalLiteralsAreExactRationals) {
  EXPECT_TRUE(same(parse("0.5"), GiNaC::numeric(1, 2)));
  EXPECT_TRUE(same(parse("1e-6"), GiNaC::numeric(1, 1000000)));
  EXPECT_TRUE(same(parse("2.5E3"), GiNaC::numeric(2500)));
  EXPECT_TRUE(same(parse("1.25e-1"), GiNaC::numeric(1, 8)));
  EXPECT_TRUE(same(parse(".5"), GiNaC::numeric(1, 2)));
  EXPECT_TRUE(same(parse("9.81"), GiNaC::numeric(981, 100)));
  EXPECT_TRUE(same(parse("0.1 + 0.2"), GiNaC::numeric(3, 10)));
  for (const char* text : {"0.5", "1e-6", "9.81", "0.1 + 0.2"}) {
    const GiNaC::ex e = parse(text);
    ASSERT_TRUE(GiNaC::is_a<GiNaC::numeric>(e)) << text;
    EXPECT_TRUE(GiNaC::ex_to<GiNaC::numeric>(e).is_rational()) << text;
  }
  EXPECT_TRUE(same(parse("2^0.5"), GiNaC::sqrt(GiNaC::ex(2))));
}

TEST_F(Expressions, SymbolsFunctionsAndPrecedence) {
  const GiNaC::ex l = model.symbol("l"), phi = model.symbol("phi"), rate = model.symbol("phi_dot");
  EXPECT_TRUE(same(parse("-l*sin(phi)^2 + phi_dot/2"),
                   -l * GiNaC::pow(GiNaC::sin(phi), 2) + rate / 2));
  EXPECT_TRUE(same(parse("atan2(l, phi)"), GiNaC::atan2(l, phi)));
  EXPECT_TRUE(same(parse("Pi/6"), GiNaC::Pi / 6));
  EXPECT_TRUE(same(parse("--l"), l));
}

TEST_F(Expressions, ErrorsPointAtTheOffendingCharacter) {
  struct Case {
    const char* text;
    std::size_t offset;
    const char* message;
  };
  for (const Case& c : {Case{"l + lenght", 4, "unknown symbol 'lenght'"},
                        Case{"2 l", 2, "expected an operator before 'l' (multiplication is written '*')"},
                        Case{"l +", 3, "unexpected end of expression"},
                        Case{"", 0, "empty expression"},
                        Case{"sin(phi", 7, "expected ',' or ')' in the arguments of 'sin'"},
                        Case{"phi)", 3, "unmatched ')'"},
                        Case{"atan2(phi)", 0, "function 'atan2' takes 2 arguments, got 1"},
                        Case{"zeta(phi)", 0, "unknown function 'zeta'"},
                        Case{"l @ 2", 2, "unexpected character '@' in an expression"},
                        Case{"1.2.3", 0, "malformed number '1.2.3'"},
                        Case{"3*I", 2, "the imaginary unit 'I' is not allowed in a model"}}) {
    try {
      parse(c.text);
      ADD_FAILURE() << "no error for '" << c.text << "'";
    } catch (const mbsgen::detail::ExpressionError& e) {
      EXPECT_EQ(e.offset(), c.offset) << c.text;
      EXPECT_EQ(std::string(e.what()), c.message) << c.text;
    }
  }
}

TEST(EditDistance, CountsTranspositionsAsOne) {
  EXPECT_EQ(mbsgen::detail::edit_distance("lenght", "length"), 1u);
  EXPECT_EQ(mbsgen::detail::edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(mbsgen::detail::edit_distance("", "abc"), 3u);
  EXPECT_EQ(mbsgen::detail::edit_distance("same", "same"), 0u);
}

// ---------------------------------------------------------------------------------------------
// Defaults and conversions

const char* const kBlock = R"(model: block
parameters: {k: 100, m: {value: 2, unit: kg}}
coordinates: [x]
bodies:
  - {name: block, translation: [x, 0, 0], mass: m, markers: [{name: p}]}
markers: [{name: wall, position: [-1, 0, 0]}]
)";

TEST(Defaults, ForceNamesAreTypeAndIndexAndUnique) {
  const mbsgen::Model m = mbsgen::read_model_string(std::string(kBlock) + R"(forces:
  - {type: spring, between: [wall, p], stiffness: k}
  - {type: spring, between: [wall, p], stiffness: k, name: spring1}
  - {type: damper, between: [wall, p], damping: 1}
  - {type: generalized, coordinate: x, value: -x_dot}
)",
                                                    "block.yaml");
  ASSERT_EQ(m.springs().size(), 2u);
  EXPECT_EQ(m.springs()[0].name, "spring2");
  EXPECT_EQ(m.springs()[1].name, "spring1");
  EXPECT_TRUE(m.springs()[0].rest_length.is_zero());
  EXPECT_EQ(m.dampers()[0].name, "damper1");
  EXPECT_EQ(m.generalized_forces()[0].name, "generalized1");
  EXPECT_EQ(m.parameters()[1].unit, "kg");
  EXPECT_EQ(m.parameters()[1].value, 2.0);
  EXPECT_EQ(m.bodies()[0].parent, mbsgen::kWorld);
  EXPECT_EQ(m.operating_point().kind, mbsgen::LinearizationPoint::Kind::given);
  EXPECT_TRUE(m.operating_point().position.empty());
}

TEST(Defaults, InertiaMapIsSymmetricAndMarkerRotationIsAMatrix) {
  const mbsgen::Model m = mbsgen::read_model_string(R"(model: gyro
parameters: {a: 1, b: 2, c: 3, d: 0.5}
coordinates: [phi]
bodies:
  - name: disk
    rotation: [{z: phi}]
    mass: 1
    inertia: {xx: a, yy: b, zz: c, xy: d}
    markers:
      - {name: turned, position: [1, 0, 0], rotation: [{z: Pi/2}]}
  - name: plate
    parent: disk
    rotation_matrix: [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    mass: 1
)",
                                                    "gyro.yaml");
  const mbsgen::Body& disk = m.bodies()[0];
  EXPECT_TRUE(same(disk.inertia[0][1], m.symbol("d")));
  EXPECT_TRUE(same(disk.inertia[1][0], m.symbol("d")));
  EXPECT_TRUE(disk.inertia[0][2].is_zero());
  const mbsgen::Mat3& r = m.marker("turned").rotation;
  const int expected[3][3] = {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      EXPECT_TRUE(same(r[i][j], expected[i][j])) << i << ',' << j << ": " << r[i][j];
      EXPECT_TRUE(same((*m.bodies()[1].rotation_matrix)[i][j], expected[i][j]));
    }
}

TEST(Errors, UnreadableFile) {
  const std::string path = kSourceDir + "/tests/data/no_such_model.yaml";
  EXPECT_EQ(error_of_file(path), path + ": error: cannot open the model file: No such file or directory");
  // A directory opens as a stream on Linux and reads as empty: named for what it is.
  const std::string dir = kSourceDir + "/tests";
  EXPECT_EQ(error_of_file(dir), dir + ": error: is a directory, not a model file (a regular file)");
  // A FIFO, a device: refused by kind before a byte is read (issue 39 §2: they blocked, or ran
  // out of memory on /dev/zero).
  EXPECT_EQ(error_of_file("/dev/zero"), "/dev/zero: error: is a character device, not a model file (a regular file)");
}

TEST(Errors, FileNameOfAStringAndColumnsInQuotedScalars) {
  EXPECT_EQ(error_of_string(std::string(kBlock) + "forces:\n  - {type: gravity, g: ['0', \"-gg\", 0]}\n"),
            "test.yaml:8:32: error: unknown symbol 'gg'");
  EXPECT_EQ(error_of_string(std::string(kBlock) + "forces:\n  - {type: gravity, g: [0, 0]}\n"),
            "test.yaml:8:24: error: gravity needs 3 components, got 2");
}

TEST(Errors, ExpressionWithEscapesIsLocatedAtTheScalar) {
  // An escape sequence: columns inside the scalar are unknown, so the scalar's own column is used.
  EXPECT_EQ(error_of_string(std::string(kBlock) +
                            "forces:\n  - {type: gravity, g: [0, \"\\x2dgg\", 0]}\n"),
            "test.yaml:8:28: error: unknown symbol 'gg'");
}

TEST(Errors, ApplicationSpecificKeysAreRejectedPerType) {
  EXPECT_EQ(error_of_string(std::string(kBlock) +
                            "forces:\n  - {type: gravity, g: [0, 0, 0], stiffness: k}\n"),
            "test.yaml:8:35: error: unknown key 'stiffness' in a gravity force (allowed: type, "
            "name, g)");
  EXPECT_EQ(error_of_string(std::string(kBlock) +
                            "outputs:\n  - {name: o, type: coordinate, coordinate: x, marker: p}\n"),
            "test.yaml:8:48: error: unknown key 'marker' in a coordinate output (allowed: name, "
            "type, unit, coordinate)");
}

// Values CLN evaluates wrongly without a word (exp(1e9999) = 1, sin(1e50) = 0, tanh(1e100) = 0)
// or that double, where the kernels compute, cannot hold. The bounds are those of double: exp
// overflows above log(DBL_MAX) = 709.78; the reference values are the C library's.
std::string with_parameter(const std::string& value) {
  return "model: v\nparameters: {c: " + value + "}\ncoordinates: [x]\n"
         "bodies:\n  - {name: b, translation: [x, 0, 0], mass: 1}\n";
}

double parameter_value(const std::string& value) {
  return mbsgen::read_model_string(with_parameter(value), "v.yaml").parameters().at(0).value;
}

TEST(Errors, ValuesCLNGetsWrongOrDoubleCannotHoldAreRefused) {
  // Columns: the argument at fault (the caret under 710 in 'exp(710)').
  EXPECT_NEAR(parameter_value("exp(709)"), std::exp(709.0), 1e-14 * std::exp(709.0));
  EXPECT_EQ(error_of_string(with_parameter("exp(710)")),
            "test.yaml:2:21: error: bad expression: exp(710) overflows double: its argument exceeds "
            "709.78");
  EXPECT_EQ(error_of_string(with_parameter("exp(1e9999)")),
            "test.yaml:2:21: error: bad expression: exp(1e+9999) overflows double: its argument "
            "exceeds 709.78");
  EXPECT_EQ(error_of_string(with_parameter("cosh(-711)")),
            "test.yaml:2:23: error: bad expression: cosh(-711) overflows double: its argument "
            "exceeds 710.47 in magnitude");
  // 1e15 is an exact integer in double; the C library reduces it exactly, as CLN does.
  EXPECT_NEAR(parameter_value("sin(1e15)"), std::sin(1e15), 1e-15);
  EXPECT_EQ(error_of_string(with_parameter("sin(1e50)")),
            "test.yaml:2:21: error: bad expression: sin(1e+50): an argument beyond 1e15 in "
            "magnitude, where its value is lost to rounding");
  EXPECT_EQ(parameter_value("tanh(1e100)"), std::tanh(1e100));  // 1, where CLN says 0
  EXPECT_EQ(parameter_value("tanh(-1e100)"), -1.0);
  EXPECT_EQ(error_of_string(with_parameter("asin(2)")),
            "test.yaml:2:17: error: cannot evaluate 'asin(2)': asin(2) has no real value");
}

// ---------------------------------------------------------------------------------------------
// Scenes

TEST(Scenes, DefaultsOfAMinimalScene) {
  const mbsgen::Model m = mbsgen::read_model_string(std::string(kBlock) + "scenes:\n  - {name: s}\n", "s.yaml");
  ASSERT_EQ(m.scenes().size(), 1u);
  const mbsgen::Scene& s = m.scenes()[0];
  EXPECT_EQ(s.analyses.size(), 3u);
  EXPECT_FALSE(s.effects.has_value());
  EXPECT_FALSE(s.inputs.has_value());
  EXPECT_FALSE(s.outputs.has_value());
  EXPECT_EQ(s.where.line, 8);
  EXPECT_EQ(s.where.column, 5);
}

TEST(Scenes, ErrorsInFrequencyRanges) {
  const std::string head = std::string(kBlock) + "scenes:\n  - name: s\n    frequency_range: ";
  EXPECT_EQ(error_of_string(head + "{from: 0, to: 10}\n"),
            "test.yaml:9:22: error: a logarithmic frequency range needs from > 0 (or spacing: linear)");
  EXPECT_EQ(error_of_string(head + "{from: 0, to: 10, spacing: linear}\n"), "");
  EXPECT_EQ(error_of_string(head + "{from: 1, to: 10, points: 1}\n"),
            "test.yaml:9:48: error: the number of points must be an integer from 2 to 10000000, got '1'");
  EXPECT_EQ(error_of_string(head + "{from: 1, to: k}\n"),
            "test.yaml:9:36: error: a frequency (Hz) must be a constant (numbers, Pi and functions only); "
            "'k' is a parameter");
  EXPECT_EQ(error_of_string(head + "{from: 1}\n"), "test.yaml:9:22: error: a frequency range needs the key 'to'");
}


// ---------------------------------------------------------------------------------------------
// Issue 14 §6, §7: physical inertia decided exactly, inputs that enter linearly, derivatives at
// the operating point, YAML tabs and aliases. (The refusals are files in tests/data/bad_models.)

namespace issue14 {

// A uniform slender rod along x: principal moments 0, m L²/12, m L²/12.
std::string rod(const std::string& m, const std::string& L, const std::string& inertia) {
  return "model: rod\nparameters: {m: " + m + ", L: " + L + "}\ncoordinates: [phi]\n"
         "bodies:\n  - {name: r, rotation: [{z: phi}], mass: m, com: [L/2, 0, 0], inertia: " +
         inertia + "}\n";
}

TEST(Inertia, SlenderRodIsAcceptedForEveryMassAndLength) {
  // Among these, m = 0.1, L = 1 and eight others were refused: Eigen's closed-form 3×3 solver
  // put the double moment B apart by ~1e-8 B, beyond the old tolerance of 1e-9.
  for (const char* m : {"0.1", "0.2", "0.3", "0.7", "1.3", "2.9"})
    for (const char* L : {"0.1", "0.3", "1", "1.7", "3"})
      EXPECT_EQ(error_of_string(rod(m, L, "{xx: 0, yy: m*L^2/12, zz: m*L^2/12}")), "")
          << "m = " << m << ", L = " << L;
}

TEST(Inertia, FlatPlateOnTheBoundaryIsAcceptedAndJustBeyondIsNot) {
  // A + B = C exactly (a flat body); then C larger by 1e-12 of itself: refused, exactly.
  EXPECT_EQ(error_of_string(rod("0.1", "1", "{xx: 0.3, yy: 0.7, zz: 1.0}")), "");
  EXPECT_EQ(error_of_string(rod("0.1", "1", "{xx: 0.3, yy: 0.7, zz: 1.000000000001}")),
            "test.yaml:5:5: error: body 'r' has an inertia tensor that violates the triangle "
            "inequality: its principal moments 0.3, 0.7, 1 kg m^2 have A + B < C, which no mass "
            "distribution gives");
}

TEST(Inertia, RotatedRodWithIrrationalEntriesIsAccepted) {
  // The rod of moments (0, B, B) turned by 45° about z: entries with sqrt(2) are not rational,
  // so the eigenvalues decide, within 32 ulps of the largest moment.
  const std::string I = "[[B/2, -B/2, 0], [-B/2, B/2, 0], [0, 0, B]]";
  for (const char* B : {"0.1/12", "sqrt(2)/12", "Pi/7"}) {
    std::string text = rod("0.1", "1", I);
    for (std::size_t at; (at = text.find('B')) != std::string::npos;) text.replace(at, 1, std::string("(") + B + ")");
    EXPECT_EQ(error_of_string(text), "") << B;
  }
}

const char* const kDriven = R"(model: driven
parameters: {m: 1, k: 100, c: 0.5}
coordinates: [x]
inputs: [F]
bodies:
  - {name: block, translation: [x, 0, 0], mass: m, markers: [{name: p}]}
markers: [{name: anchor, position: [-1, 0, 0]}, {name: origin}]
forces:
  - {type: spring, between: [anchor, p], stiffness: k, rest_length: 1}
)";

TEST(Inputs, AnInputWrittenWithSquaresThatCancelIsLinearAndItsColumnOfBIsExact) {
  // 3F + xF − (F+1)² + F² + 1 = F (1 + x): linear in F, B = −∂(k − q)/∂F = 1 + x0 = 1.
  const mbsgen::Model model = mbsgen::read_model_string(
      std::string(kDriven) + "  - {type: generalized, coordinate: x, value: 3*F + x*F - (F+1)^2 + F^2 + 1}\n"
                             "  - {type: applied, marker: p, force: [2*F*cos(x), 0, 0]}\n",
      "driven.yaml");
  mbsgen::Equations eq = mbsgen::derive(model);
  mbsgen::LinearEquations lin = mbsgen::linearize(eq);
  ASSERT_NO_THROW(mbsgen::check_operating_point(eq, lin));
  const GiNaC::ex B = eq.program.inline_all(lin.B[0][0]).subs(GiNaC::lst{model.symbol("x")}, GiNaC::lst{0});
  EXPECT_TRUE(same(B, 3)) << B;  // 1 from the generalized force, 2 cos(0) from the applied force
}

TEST(Derivatives, NonSmoothFunctionsAwayFromTheirKinkAndZeroLengthSpringsAreAccepted) {
  // abs(x - 1) at x = 0 is differentiable; sqrt(x + 4) too; a spring of rest length 0 between
  // coincident markers is V = k L²/2, smooth.
  EXPECT_EQ(error_of_string(std::string(kDriven) +
                            "  - {type: generalized, coordinate: x, value: -c*abs(x - 1) + c*sqrt(x + 4) - c}\n"
                            "  - {type: spring, between: [origin, p], stiffness: k}\n"),
            "");
  // The same law at a rest point where the kink is reached is refused, at the call.
  EXPECT_EQ(error_of_string(std::string(kDriven) +
                            "  - {type: generalized, coordinate: x, value: -c*abs(x - 1)}\n"
                            "operating_point: {position: {x: 1}}\n"),
            "test.yaml:10:50: error: abs(x - 1) is not differentiable at the operating point, where "
            "-1+x = 0 (the linear model needs its derivative there: use a law that is smooth at the "
            "operating point, or another operating point)");
}

TEST(Yaml, TabsInCommentsAndFlowCollectionsAreFine) {
  EXPECT_EQ(error_of_string("model: t\ncoordinates: [x,\tx2]\nbodies:\n\t# a comment\n"
                            "  - {name: b, translation: [x + x2, 0, 0], mass: 1}\n"),
            "");
}

TEST(Yaml, AnAliasThatDuplicatesNothingIsFine) {
  EXPECT_EQ(error_of_string("model: a\ncoordinates: [x]\nbodies:\n"
                            "  - {name: b, translation: [x, 0, 0], mass: 1, com: &c [0, 0, 0], "
                            "markers: [{name: p, position: *c}]}\n"),
            "");
}

}  // namespace issue14

}  // namespace

// ---------------------------------------------------------------------------------------------
// Closed loops and loads (issue 15)

TEST(Linkages, ContentsAsWritten) {
  const mbsgen::Model m = mbsgen::read_model_file(kSourceDir + "/models/linkages/slider_crank.yaml");
  ASSERT_EQ(m.constraints().size(), 1u);
  const mbsgen::Constraint& pin = m.constraints()[0];
  EXPECT_EQ(pin.name, "pin");
  EXPECT_EQ(pin.kind, mbsgen::ConstraintKind::revolute);
  EXPECT_EQ(pin.marker_a, "rod_end");
  EXPECT_EQ(pin.marker_b, "slider_pin");
  EXPECT_GT(pin.where.line, 0);
  ASSERT_EQ(m.independent_coordinates().size(), 1u);
  EXPECT_EQ(m.independent_coordinates()[0].name, "th1");
  const mbsgen::Output& guide = m.outputs()[3];
  EXPECT_EQ(guide.kind, mbsgen::OutputKind::reaction);
  EXPECT_EQ(guide.reaction_of, "slider");
  EXPECT_EQ(guide.quantity, mbsgen::ForceQuantity::force);
  EXPECT_TRUE(guide.frame_marker.empty());
  EXPECT_TRUE((guide.direction[1] - 1).is_zero());
  const mbsgen::Output& spring = m.outputs()[8];
  EXPECT_EQ(spring.kind, mbsgen::OutputKind::force);
  EXPECT_EQ(spring.elements, std::vector<std::string>{"spring"});
}

TEST(Linkages, DefaultNamesKindsAndFrames) {
  const mbsgen::Model m = mbsgen::read_model_string(R"(model: loops
parameters: {L: 0.5}
coordinates: [x, y, z]
bodies:
  - {name: bob, translation: [x, y, z], mass: 1, markers: [{name: p}]}
markers: [{name: o}]
forces:
  - {name: holder, type: spring, between: [o, p], stiffness: 10}
constraints:
  - {type: distance, between: [o, p], length: L}
  - {type: expression, expression: z}
  - {type: planar, between: [o, p]}
outputs:
  - {name: t, type: reaction, of: distance1, quantity: torque, direction: [0, 0, 1], frame: p}
  - {name: f, type: force, elements: [holder], direction: [1, 0, 0], frame: marker, quantity: torque}
operating_point: {position: {y: -L}}
)", "loops.yaml");
  ASSERT_EQ(m.constraints().size(), 3u);
  EXPECT_EQ(m.constraints()[0].name, "distance1");
  EXPECT_TRUE((m.constraints()[0].length - m.symbol("L")).is_zero());
  EXPECT_EQ(m.constraints()[1].name, "expression1");
  EXPECT_EQ(m.constraints()[1].kind, mbsgen::ConstraintKind::expression);
  EXPECT_TRUE((m.constraints()[1].expression - m.symbol("z")).is_zero());
  EXPECT_EQ(m.constraints()[2].name, "planar1");
  EXPECT_EQ(m.outputs()[0].quantity, mbsgen::ForceQuantity::torque);
  EXPECT_EQ(m.outputs()[0].frame_marker, "p");
  EXPECT_EQ(m.outputs()[1].force_frame, mbsgen::ForceFrame::marker);
}

// The complete four-bar of docs/model-format.md reads, derives and closes its loop, and is the
// model file models/linkages/four_bar.yaml up to its comments and outputs.
TEST(Linkages, DocumentationFourBarReads) {
  std::ifstream in(kSourceDir + "/docs/model-format.md");
  std::string line, yaml;
  bool after = false, inside = false;
  while (std::getline(in, line)) {
    if (line.rfind("A complete four-bar", 0) == 0) after = true;
    if (after && !inside && line == "```yaml") {
      inside = true;
      continue;
    }
    if (inside && line == "```") break;
    if (inside) yaml += line + "\n";
  }
  ASSERT_FALSE(yaml.empty());
  const mbsgen::Model m = mbsgen::read_model_string(yaml, "model-format.md");
  mbsgen::Equations eq = mbsgen::derive(m);
  EXPECT_EQ(eq.loops.equations.size(), 2u);
  ASSERT_EQ(eq.loops.independent.size(), 1u);
  EXPECT_EQ(m.coordinates()[eq.loops.independent[0]].name, "th1");
  const mbsgen::Model file = mbsgen::read_model_file(kSourceDir + "/models/linkages/four_bar.yaml");
  ASSERT_EQ(m.parameters().size(), file.parameters().size());
  for (std::size_t i = 0; i < m.parameters().size(); ++i)
    EXPECT_EQ(m.parameters()[i].value, file.parameters()[i].value) << m.parameters()[i].name;
}

// The model file's conditions on masses, inertias, lengths and radii that depend on parameters
// are listed for the run time (Model::physical_checks, issue 39 §1); those on constants were
// decided by validate() and are not. The Whipple bicycle: four bodies with parameter masses
// (the two massless frames are constant), two wheel radii; none of the values is changed.
TEST(PhysicalChecks, EveryParameterDependentConditionIsListed) {
  const mbsgen::Model bike = mbsgen::read_model_file(kSourceDir + "/models/bicycle/whipple_benchmark.yaml");
  const std::vector<mbsgen::PhysicalCheck> checks = bike.physical_checks();
  std::vector<std::string> labels;
  for (const auto& c : checks) labels.push_back(c.label);
  EXPECT_EQ(labels, (std::vector<std::string>{"body 'rear_frame'", "body 'rear_wheel'", "body 'front_frame'",
                                               "body 'front_wheel'", "the wheel radius of rolling constraint 'rear_contact'",
                                               "the wheel radius of rolling constraint 'front_contact'"}));
  ASSERT_EQ(checks.size(), 6u);
  EXPECT_EQ(checks[1].kind, mbsgen::PhysicalCheck::Kind::body);
  // Each parameter of the rear wheel's values once (in the model file's parameter order).
  std::vector<std::string> rear = checks[1].parameters;
  std::sort(rear.begin(), rear.end());
  EXPECT_EQ(rear, (std::vector<std::string>{"IRxx", "IRyy", "mR"}));
  ASSERT_EQ(checks[1].values.size(), 7u);
  EXPECT_TRUE(same(checks[1].values[0], bike.symbol("mR")));
  EXPECT_TRUE(same(checks[1].values[3], bike.symbol("IRxx")));  // zz: IRxx
  EXPECT_TRUE(same(checks[1].values[4], 0));                    // no xy product
  EXPECT_EQ(checks[4].kind, mbsgen::PhysicalCheck::Kind::positive);
  EXPECT_EQ(checks[4].parameters, std::vector<std::string>{"rR"});
  EXPECT_EQ(checks[4].unit, "m");
  // A spring's rest length: nonnegative; the physical pendulum's m l^2/12 names both parameters.
  const mbsgen::Model chain = mbsgen::read_model_file(kSourceDir + "/models/textbook/spring_chain_fixed_free.yaml");
  bool rest = false;
  for (const auto& c : chain.physical_checks())
    rest = rest || (c.kind == mbsgen::PhysicalCheck::Kind::nonnegative && c.parameters == std::vector<std::string>{"a"});
  EXPECT_TRUE(rest);
  const mbsgen::Model rod = mbsgen::read_model_file(kSourceDir + "/models/textbook/physical_pendulum.yaml");
  ASSERT_EQ(rod.physical_checks().size(), 1u);
  EXPECT_EQ(rod.physical_checks()[0].parameters, (std::vector<std::string>{"m", "l"}));
}
