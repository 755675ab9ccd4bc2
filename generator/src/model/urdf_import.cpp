// URDF → mbsgen model file (urdf_import.hpp says what becomes what; docs/urdf.md).
#include "mbsgen/generator/model/urdf_import.hpp"

#include "mbsgen/generator/model/escape.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#ifdef MBSGEN_HAVE_URDF
#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>
#endif

namespace mbsgen {

bool is_urdf_path(const std::string& path) {
  if (path.size() < 5) return false;
  std::string ext = path.substr(path.size() - 5);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".urdf";
}

std::string urdf_import_checksum(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a: a change, not an adversary, is what it detects
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ULL;
  char buf[64];
  std::snprintf(buf, sizeof buf, "# mbsgen import checksum %016llx\n", static_cast<unsigned long long>(h));
  return buf;
}

UrdfImport import_urdf_file(const std::string& path, const UrdfImportOptions& options) {
  return import_urdf_string(read_model_text(path), path, options);
}

#ifndef MBSGEN_HAVE_URDF

UrdfImport import_urdf_string(const std::string&, const std::string& file_name, const UrdfImportOptions&) {
  throw ModelError({file_name, 0, 0},
                   "this mbsgen was built without URDF support (urdfdom: install liburdfdom-dev, scripts/deps.sh, "
                   "and build again)");
}

#else

namespace {

using Vec = Eigen::Vector3d;
using Mat = Eigen::Matrix3d;

// ---- text ---------------------------------------------------------------------------------------

// The shortest decimal that reads back as x ("0.1", "1.5708", "1e-05"); exact in the model file,
// where decimals are exact rationals.
std::string num(double x) {
  if (x == 0) return "0";
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// Text inside a YAML comment or a double-quoted YAML string: printable ASCII as it is, every other
// byte as \xNN, so that nothing of a URDF's names can end the comment or the string.
std::string printable(const std::string& s, bool quoted) {
  std::string out;
  for (unsigned char c : s) {
    if (c >= 0x20 && c < 0x7f && !(quoted && (c == '"' || c == '\\'))) {
      out += static_cast<char>(c);
    } else if (quoted && (c == '"' || c == '\\')) {
      out += '\\';
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return out;
}
std::string quoted(const std::string& s) { return "\"" + printable(s, true) + "\""; }
std::string comment(const std::string& s) { return printable(s, false); }

// A name of the model format (a letter, then letters, digits and _), unique in its namespace.
class Names {
 public:
  std::string take(const std::string& raw, std::vector<std::string>* notes, const char* what) {
    std::string id;
    for (unsigned char c : raw) id += (std::isalnum(c) || c == '_') && c < 0x80 ? static_cast<char>(c) : '_';
    if (id.empty() || !std::isalpha(static_cast<unsigned char>(id[0]))) id = "n" + id;
    // The reader's reserved words, and the plain scalars YAML reads as null or a boolean.
    static const std::set<std::string> reserved = {
        "sin",  "cos",  "tan",  "exp",  "log",  "sqrt", "abs",  "asin", "acos", "atan", "atan2", "sinh",
        "cosh", "tanh", "Pi",   "I",    "Euler", "Catalan", "pow", "world", "null", "Null", "NULL", "true",
        "True", "TRUE", "false", "False", "FALSE", "y", "Y", "n", "N", "yes", "Yes", "YES", "no", "No", "NO",
        "on",   "On",   "ON",   "off",  "Off",  "OFF"};
    // A symbol ending in _dot could be a coordinate's rate: none does.
    if (id.size() >= 4 && id.compare(id.size() - 4, 4, "_dot") == 0) id += "_";
    std::string name = id;
    for (int k = 2; reserved.count(name) || used_.count(name); ++k) name = id + "_" + std::to_string(k);
    used_.insert(name);
    if (name != raw && notes && what) notes->push_back(std::string(what) + " '" + comment(raw) + "' is named " + name);
    return name;
  }
  void reserve(const std::string& name) { used_.insert(name); }

 private:
  std::set<std::string> used_;
};

// ---- geometry -------------------------------------------------------------------------------------

Mat rpy_matrix(const Vec& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vec::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vec::UnitX()))
      .toRotationMatrix();
}

// rpy as the model format's intrinsic rotations: R = Rz(yaw) Ry(pitch) Rx(roll).
std::vector<std::string> rpy_rotations(const Vec& rpy) {
  std::vector<std::string> out;
  if (rpy.z() != 0) out.push_back("{z: " + num(rpy.z()) + "}");
  if (rpy.y() != 0) out.push_back("{y: " + num(rpy.y()) + "}");
  if (rpy.x() != 0) out.push_back("{x: " + num(rpy.x()) + "}");
  return out;
}

// c0 + a q, written short.
std::string affine(double c0, double a, const std::string& q) {
  std::string t = a == 0 ? "" : a == 1 ? q : a == -1 ? "-" + q : num(a) + "*" + q;
  if (c0 == 0) return t.empty() ? "0" : t;
  if (t.empty()) return num(c0);
  return num(c0) + (t[0] == '-' ? " - " + t.substr(1) : " + " + t);
}

std::string list(const std::vector<std::string>& items) {
  std::string s = "[";
  for (std::size_t i = 0; i < items.size(); ++i) s += (i ? ", " : "") + items[i];
  return s + "]";
}

// ---- the URDF, read -------------------------------------------------------------------------------

struct Pose {
  Vec xyz = Vec::Zero(), rpy = Vec::Zero();
  Eigen::Isometry3d transform() const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = rpy_matrix(rpy);
    t.translation() = xyz;
    return t;
  }
};

struct Link {
  std::string raw, id;  // the URDF's name; the body's (and parameters') name
  int line = 0, inertial_line = 0;
  bool massive = false, rotated = false;  // rotated: an <inertial> rpy turned the tensor
  double mass = 0;
  Vec com = Vec::Zero();
  Mat inertia = Mat::Zero();  // about the centre of mass, link frame
  std::vector<std::string> children;  // joints, in the file's order
  // Import: the body whose frame is this link's (or "" for a fixed leaf, a marker), and the body
  // that carries its mass with the link frame's pose in it.
  std::string frame_body, owner;
  Eigen::Isometry3d in_owner = Eigen::Isometry3d::Identity();
  std::string marker_body;  // a fixed leaf: the body its frame is on, at `marker_pose`
  Pose marker_pose;
};

struct Joint {
  std::string raw, type, parent, child;
  int line = 0;
  Pose origin;
  Vec axis = Vec::UnitX();
  std::vector<std::string> coordinates;  // model names
  std::string mimic;                     // the raw name of the joint it mimics
  double multiplier = 1, offset = 0, damping = 0, friction = 0;
  std::string limits;                    // as a comment
};

struct Body {
  std::string name, parent, translation, rotation, source;  // rotation: "rotation: [..]" or "rotation_matrix: .."
};

class Importer {
 public:
  Importer(const std::string& text, const std::string& file, const UrdfImportOptions& options)
      : text_(text), file_(file), opt_(options) {}
  UrdfImport run();

 private:
  [[noreturn]] void fail(const TiXmlNode* at, const std::string& what) const {
    throw ModelError({file_, at ? at->Row() : 0, at ? at->Column() : 0}, what);
  }
  void parse_xml();
  void check_with_urdfdom();
  Vec numbers(const TiXmlElement* e, const char* attribute, const Vec& fallback) const;
  double number(const TiXmlElement* e, const char* attribute, double fallback) const;
  Pose pose_of(const TiXmlElement* parent) const;
  void read_link(const TiXmlElement* e);
  void read_joint(const TiXmlElement* e);
  void check_inertia(const Link& l, const TiXmlElement* at) const;
  void check_tree();
  void check_mimics_and_options();
  void place_root();
  void place(const std::string& joint);
  std::string intermediate_frame(const Joint& j, const std::string& parent_body);
  void add_coordinates(Joint& j);
  void compose_masses();
  void settle(Mat& inertia, Vec& c, const std::string& body);
  void write(std::ostringstream& y);
  void write_parameters(std::ostringstream& y);
  void write_coordinates(std::ostringstream& y);
  void write_bodies(std::ostringstream& y);
  void write_forces(std::ostringstream& y);
  void write_outputs(std::ostringstream& y);
  std::string where(int line) const { return comment(std::filesystem::path(file_).filename().string()) + ":" + std::to_string(line); }

  const std::string& text_;
  const std::string file_;
  const UrdfImportOptions& opt_;
  TiXmlDocument doc_;
  std::string robot_;
  std::vector<std::string> link_order_, joint_order_;
  std::map<std::string, Link> links_;
  std::map<std::string, Joint> joints_;
  std::map<std::string, const TiXmlElement*> joint_elements_;
  std::map<std::string, int> skipped_;  // element → count
  std::string root_;
  Names symbols_, entities_;
  std::vector<std::string> notes_;
  std::vector<Body> bodies_;
  std::vector<std::pair<std::string, std::string>> coordinates_;  // name, comment
  std::vector<std::string> parameters_;                            // YAML lines
  struct MassParameters {
    std::string mass;
    std::array<std::string, 3> com;
    std::array<std::string, 6> inertia;  // xx yy zz xy xz yz
  };
  std::map<std::string, MassParameters> masses_;  // body → parameter names
};

// ---- reading ----------------------------------------------------------------------------------

// TinyXML parses (and frees) nested elements recursively: a file nested deeper than any robot
// is refused before it is parsed. Counts start tags that do not close themselves, minus end tags
// (comments, declarations and CDATA skipped); a conservative bound, not a parser.
void refuse_deep_nesting(const std::string& text, const std::string& file) {
  constexpr int kMaxDepth = 64;
  int depth = 0, line = 1;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<' || i + 1 >= text.size()) continue;
    const char c = text[i + 1];
    if (c == '!' || c == '?') {
      const char* end = text.compare(i, 4, "<!--") == 0 ? "-->" : text.compare(i, 9, "<![CDATA[") == 0 ? "]]>" : ">";
      const std::size_t j = text.find(end, i);
      if (j == std::string::npos) return;  // TinyXML says what is wrong
      line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(i), text.begin() + static_cast<std::ptrdiff_t>(j), '\n'));
      i = j;
      continue;
    }
    if (c == '/') {
      --depth;
      continue;
    }
    const std::size_t close = text.find('>', i);
    if (close == std::string::npos) return;
    if (text[close - 1] != '/' && ++depth > kMaxDepth)
      throw ModelError({file, line, 0}, "elements nested more than " + std::to_string(kMaxDepth) +
                                            " deep: not a robot description");
  }
}

void Importer::parse_xml() {
  refuse_deep_nesting(text_, file_);
  doc_.SetTabSize(1);
  doc_.Parse(text_.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc_.Error())
    throw ModelError({file_, std::max(doc_.ErrorRow(), 0), std::max(doc_.ErrorCol(), 0)},
                     std::string("malformed XML: ") + doc_.ErrorDesc());
  const TiXmlElement* robot = doc_.RootElement();
  if (!robot || std::string(robot->Value()) != "robot")
    fail(robot, "not a URDF file: the root element is <" + std::string(robot ? robot->Value() : "") + ">, not <robot>");
  robot_ = robot->Attribute("name") ? robot->Attribute("name") : "robot";
  for (const TiXmlElement* e = robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->Value();
    if (tag == "link")
      read_link(e);
    else if (tag == "joint")
      joint_elements_[e->Attribute("name") ? e->Attribute("name") : ""] = e;
    else
      ++skipped_["<" + comment(tag) + ">"];
  }
  constexpr std::size_t kMaxLinks = 10000;
  if (links_.size() > kMaxLinks || joint_elements_.size() > kMaxLinks)
    fail(robot, "more than " + std::to_string(kMaxLinks) + " links or joints: not imported");
  for (const TiXmlElement* e = robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) read_joint(e);
}

// urdfdom checks each element's attributes and the tree it can build (one root, every joint's
// links known; not a link with two parents or a cycle beside the root: check_tree does) and
// reports through console_bridge: its message, at the element it names.
class Captured : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::vector<std::string> errors;
};

void Importer::check_with_urdfdom() {
  static std::mutex console;  // console_bridge's handler is one per process
  std::lock_guard<std::mutex> lock(console);
  Captured captured;
  console_bridge::useOutputHandler(&captured);
  urdf::ModelInterfaceSharedPtr model;
  std::string thrown;
  // urdfdom 3.0 passes the text of a bad number to console_bridge as a printf format: its copy
  // has no '%' (a '%' is in no valid number; the importer reads the numbers from its own parse).
  std::string neutral = text_;
  std::replace(neutral.begin(), neutral.end(), '%', '?');
  try {
    model = urdf::parseURDF(neutral);
  } catch (const std::exception& e) {
    thrown = e.what();
  }
  console_bridge::restorePreviousOutputHandler();
  if (model && thrown.empty()) return;
  std::string message = thrown.empty() ? "" : comment(thrown);
  for (const auto& e : captured.errors) message += (message.empty() ? "" : "; ") + comment(e);
  if (message.empty()) message = "urdfdom refused the file";
  // The element whose name the message quotes first ("[name]" or "'name'").
  const TiXmlNode* at = doc_.RootElement();
  std::size_t best = std::string::npos;
  for (const TiXmlElement* e = doc_.RootElement()->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const char* name = e->Attribute("name");
    if (!name || !*name) continue;
    const std::size_t hit = std::min(message.find("[" + std::string(name) + "]"), message.find("'" + std::string(name) + "'"));
    if (hit < best) best = hit, at = e;
  }
  fail(at, "urdfdom: " + message);
}

// One number of an attribute, all of `w`: xs:double's optional sign, no locale; finite.
bool finite_number(const std::string& w, double& x) {
  const std::size_t skip = w.size() > 1 && w[0] == '+' ? 1 : 0;
  const auto r = std::from_chars(w.data() + skip, w.data() + w.size(), x);
  return r.ec == std::errc() && r.ptr == w.data() + w.size() && std::isfinite(x);
}

Vec Importer::numbers(const TiXmlElement* e, const char* attribute, const Vec& fallback) const {
  const char* text = e ? e->Attribute(attribute) : nullptr;
  if (!text) return fallback;
  std::istringstream in(text);
  std::vector<double> v;
  for (std::string w; in >> w;) {
    double x = 0;
    if (!finite_number(w, x))
      fail(e, std::string(attribute) + "=\"" + comment(text) + "\": '" + comment(w) + "' is not a finite number");
    v.push_back(x);
  }
  if (v.size() != 3) fail(e, std::string(attribute) + "=\"" + comment(text) + "\": three numbers expected");
  return Vec(v[0], v[1], v[2]);
}

double Importer::number(const TiXmlElement* e, const char* attribute, double fallback) const {
  const char* text = e ? e->Attribute(attribute) : nullptr;
  if (!text) return fallback;
  std::string w(text);
  w.erase(0, w.find_first_not_of(" \t\r\n"));
  w.erase(w.find_last_not_of(" \t\r\n") + 1);
  double x = 0;
  if (!finite_number(w, x))
    fail(e, std::string(attribute) + "=\"" + comment(text) + "\" is not a finite number");
  return x;
}

Pose Importer::pose_of(const TiXmlElement* parent) const {
  const TiXmlElement* o = parent ? parent->FirstChildElement("origin") : nullptr;
  return {numbers(o, "xyz", Vec::Zero()), numbers(o, "rpy", Vec::Zero())};
}

void Importer::check_inertia(const Link& l, const TiXmlElement* at) const {
  const std::string who = "link '" + comment(l.raw) + "'";
  if (l.mass < 0) fail(at, who + ": the mass " + num(l.mass) + " kg is negative");
  const Eigen::SelfAdjointEigenSolver<Mat> eig(l.inertia);
  const Vec m = eig.eigenvalues();  // ascending
  const double tol = 1e-9 * std::max(m(2), 0.0);
  if (l.mass == 0 && m.cwiseAbs().maxCoeff() > 0)
    fail(at, who + ": a zero mass with a nonzero inertia");
  if (m(0) < -tol || m(0) + m(1) < m(2) - tol)
    fail(at, who + ": the inertia is not physical: principal moments " + num(m(0)) + ", " + num(m(1)) + ", " +
                 num(m(2)) + " kg m^2 (each must be >= 0 and A + B >= C)");
}

void Importer::read_link(const TiXmlElement* e) {
  Link l;
  l.raw = e->Attribute("name") ? e->Attribute("name") : "";
  l.line = e->Row();
  for (const TiXmlElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement())
    if (std::string(c->Value()) != "inertial") ++skipped_["<" + comment(c->Value()) + ">"];
  if (const TiXmlElement* in = e->FirstChildElement("inertial")) {
    const Pose p = pose_of(in);
    const TiXmlElement* mass = in->FirstChildElement("mass");
    const TiXmlElement* i = in->FirstChildElement("inertia");
    l.inertial_line = in->Row();
    l.mass = number(mass, "value", 0);
    Mat tensor;
    tensor << number(i, "ixx", 0), number(i, "ixy", 0), number(i, "ixz", 0), number(i, "ixy", 0),
        number(i, "iyy", 0), number(i, "iyz", 0), number(i, "ixz", 0), number(i, "iyz", 0), number(i, "izz", 0);
    l.inertia = tensor;
    check_inertia(l, i ? i : in);
    const Mat r = rpy_matrix(p.rpy);
    l.inertia = r * tensor * r.transpose();
    l.rotated = !p.rpy.isZero(0);
    l.com = p.xyz;
    l.massive = l.mass > 0;
  }
  link_order_.push_back(l.raw);
  links_[l.raw] = std::move(l);
}

void Importer::read_joint(const TiXmlElement* e) {
  Joint j;
  j.raw = e->Attribute("name") ? e->Attribute("name") : "";
  j.type = e->Attribute("type") ? e->Attribute("type") : "";
  j.line = e->Row();
  const TiXmlElement* parent = e->FirstChildElement("parent");
  const TiXmlElement* child = e->FirstChildElement("child");
  j.parent = parent && parent->Attribute("link") ? parent->Attribute("link") : "";
  j.child = child && child->Attribute("link") ? child->Attribute("link") : "";
  j.origin = pose_of(e);
  const TiXmlElement* axis = e->FirstChildElement("axis");
  j.axis = numbers(axis, "xyz", Vec::UnitX());
  if (j.type != "fixed" && j.type != "floating") {
    const double n = j.axis.norm();
    if (n == 0) fail(axis ? axis : e, "joint '" + comment(j.raw) + "': the axis is zero");
    if (std::abs(n - 1) > 1e-12) {
      notes_.push_back("joint '" + comment(j.raw) + "': axis " + num(j.axis.x()) + " " + num(j.axis.y()) + " " +
                       num(j.axis.z()) + " normalized");
      j.axis /= n;
    }
  }
  if (const TiXmlElement* m = e->FirstChildElement("mimic")) {
    j.mimic = m->Attribute("joint") ? m->Attribute("joint") : "";
    j.multiplier = number(m, "multiplier", 1);
    j.offset = number(m, "offset", 0);
  }
  if (const TiXmlElement* d = e->FirstChildElement("dynamics")) {
    j.damping = number(d, "damping", 0);
    j.friction = number(d, "friction", 0);
    if (j.damping < 0 || j.friction < 0) fail(d, "joint '" + comment(j.raw) + "': negative damping or friction");
  }
  if (const TiXmlElement* l = e->FirstChildElement("limit")) {
    const std::string unit = j.type == "prismatic" ? "m" : "rad";
    std::ostringstream s;
    if (j.type != "continuous" && (l->Attribute("lower") || l->Attribute("upper")))
      s << "limits [" << num(number(l, "lower", 0)) << ", " << num(number(l, "upper", 0)) << "] " << unit << ", ";
    s << "effort " << num(number(l, "effort", 0)) << (unit == "m" ? " N" : " N m") << ", velocity "
      << num(number(l, "velocity", 0)) << " " << unit << "/s";
    j.limits = s.str();
  }
  for (const TiXmlElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Value();
    if (tag == "calibration" || tag == "safety_controller") ++skipped_["<" + tag + ">"];
  }
  joint_order_.push_back(j.raw);
  joints_[j.raw] = std::move(j);
}

// ---- placing the links ----------------------------------------------------------------------------

void Importer::place_root() {
  Link& root = links_.at(root_);
  if (!opt_.floating_base) {
    root.frame_body = root.owner = "world";
    return;
  }
  Body b;
  b.name = root.id;
  b.parent = "world";
  std::vector<std::string> q;
  for (const char* s : {"x", "y", "z", "yaw", "pitch", "roll"}) q.push_back(symbols_.take("base_" + std::string(s), nullptr, nullptr));
  for (int k = 0; k < 6; ++k) {
    coordinates_.push_back({q[k], k < 3 ? "m" : "rad"});
    symbols_.reserve(q[k] + "_dot");
  }
  b.translation = list({q[0], q[1], q[2]});
  b.rotation = "rotation: [{z: " + q[3] + "}, {y: " + q[4] + "}, {x: " + q[5] + "}]";
  b.source = "the floating base (import option): link '" + comment(root.raw) + "' (" + where(root.line) + ")";
  root.frame_body = root.owner = b.name;
  bodies_.push_back(b);
}

// A massless frame at the joint's origin, where the joint's motion is not one elementary rotation.
std::string Importer::intermediate_frame(const Joint& j, const std::string& parent_body) {
  Body f;
  f.name = entities_.take(links_.at(j.child).id + "_joint_frame", nullptr, nullptr);
  f.parent = parent_body;
  f.translation = list({num(j.origin.xyz.x()), num(j.origin.xyz.y()), num(j.origin.xyz.z())});
  const auto rot = rpy_rotations(j.origin.rpy);
  f.rotation = rot.empty() ? "" : "rotation: " + list(rot);
  f.source = "origin of joint '" + comment(j.raw) + "' (" + where(j.line) + ")";
  bodies_.push_back(f);
  return f.name;
}

void Importer::add_coordinates(Joint& j) {
  const std::string base = symbols_.take(j.raw, &notes_, "joint");
  if (j.type == "floating") {
    for (const char* s : {"_x", "_y", "_z", "_yaw", "_pitch", "_roll"})
      j.coordinates.push_back(symbols_.take(base + s, nullptr, nullptr));
  } else if (j.type == "planar") {
    for (const char* s : {"_u", "_v", "_angle"}) j.coordinates.push_back(symbols_.take(base + s, nullptr, nullptr));
  } else {
    j.coordinates.push_back(base);
  }
  for (const auto& q : j.coordinates) symbols_.reserve(q + "_dot");
  for (std::size_t k = 0; k < j.coordinates.size(); ++k) {
    const bool angle = j.type == "revolute" || j.type == "continuous" || (j.type == "floating" && k >= 3) ||
                       (j.type == "planar" && k == 2);
    std::string c = "joint '" + comment(j.raw) + "' (" + where(j.line) + "): " + j.type;
    if (!j.limits.empty()) c += ", " + j.limits;
    coordinates_.push_back({j.coordinates[k], std::string(angle ? "rad" : "m") + "   # " + c});
  }
}

void Importer::place(const std::string& name) {
  Joint& j = joints_.at(name);
  Link& parent = links_.at(j.parent);
  Link& child = links_.at(j.child);
  const std::string parent_body = parent.frame_body;
  if (j.type == "fixed") {
    child.owner = parent.owner;
    child.in_owner = parent.in_owner * j.origin.transform();
    if (child.children.empty()) {  // a frame: a marker where an output asks for it
      child.marker_body = parent_body;
      child.marker_pose = j.origin;
    } else {  // a massless body (the links beyond hang from its frame)
      Body b;
      b.name = child.id;
      b.parent = parent_body;
      b.translation = list({num(j.origin.xyz.x()), num(j.origin.xyz.y()), num(j.origin.xyz.z())});
      const auto rot = rpy_rotations(j.origin.rpy);
      b.rotation = rot.empty() ? "" : "rotation: " + list(rot);
      b.source = "link '" + comment(child.raw) + "' (" + where(child.line) + ") on fixed joint '" + comment(j.raw) +
                 "' (" + where(j.line) + "); its mass is lumped into " + child.owner;
      bodies_.push_back(b);
      child.frame_body = b.name;
    }
  } else {
    add_coordinates(j);
    const auto& q = j.coordinates;
    const Vec& a = j.axis;
    const bool plain = j.origin.rpy.isZero(0);
    int k = -1;  // the axis along which `a` lies, if it does
    for (int i = 0; i < 3; ++i)
      if (std::abs(a(i)) == 1) k = i;
    const char* letter[] = {"x", "y", "z"};
    Body b;
    b.name = child.id;
    b.source = "link '" + comment(child.raw) + "' (" + where(child.line) + "), joint '" + comment(j.raw) + "' (" +
               where(j.line) + ")";
    const bool rotational = j.type == "revolute" || j.type == "continuous";
    if (rotational && k >= 0) {  // origin and motion in one body
      b.parent = parent_body;
      b.translation = list({num(j.origin.xyz.x()), num(j.origin.xyz.y()), num(j.origin.xyz.z())});
      auto rot = rpy_rotations(j.origin.rpy);
      rot.push_back(std::string("{") + letter[k] + ": " + (a(k) > 0 ? q[0] : "-" + q[0]) + "}");
      b.rotation = "rotation: " + list(rot);
    } else {
      const Vec o = plain ? j.origin.xyz : Vec::Zero();
      b.parent = plain ? parent_body : intermediate_frame(j, parent_body);
      if (rotational) {  // Rodrigues: R = cos q E + sin q [a]x + (1 - cos q) a a^T
        const std::string c = "cos(" + q[0] + ")", s = "sin(" + q[0] + ")", v = "(1 - cos(" + q[0] + "))";
        auto entry = [&](int r, int col) {
          std::string e = (r == col ? c : "0");
          const double cross[3][3] = {{0, -a.z(), a.y()}, {a.z(), 0, -a.x()}, {-a.y(), a.x(), 0}};
          if (cross[r][col] != 0) e += " + " + num(cross[r][col]) + "*" + s;
          const double outer = a(r) * a(col);
          if (outer != 0) e += " + " + num(outer) + "*" + v;
          return e;
        };
        std::string m = "rotation_matrix: [";
        for (int r = 0; r < 3; ++r) m += std::string(r ? ", " : "") + list({entry(r, 0), entry(r, 1), entry(r, 2)});
        b.rotation = m + "]";
        b.translation = list({num(o.x()), num(o.y()), num(o.z())});
      } else if (j.type == "prismatic") {
        b.translation = list({affine(o.x(), a.x(), q[0]), affine(o.y(), a.y(), q[0]), affine(o.z(), a.z(), q[0])});
      } else if (j.type == "floating") {
        b.translation = list({affine(o.x(), 1, q[0]), affine(o.y(), 1, q[1]), affine(o.z(), 1, q[2])});
        b.rotation = "rotation: [{z: " + q[3] + "}, {y: " + q[4] + "}, {x: " + q[5] + "}]";
      } else {  // planar, normal along axis k
        const TiXmlElement* at = joint_elements_.at(name);
        if (k < 0) fail(at, "joint '" + comment(j.raw) + "': a planar joint's normal must lie along x, y or z");
        const int u = (k + 1) % 3, w = (k + 2) % 3;
        std::vector<std::string> t(3);
        t[k] = num(o(k));
        t[u] = affine(o(u), 1, q[0]);
        t[w] = affine(o(w), 1, q[1]);
        b.translation = list(t);
        b.rotation = std::string("rotation: [{") + letter[k] + ": " + (a(k) > 0 ? q[2] : "-" + q[2]) + "}]";
      }
    }
    bodies_.push_back(b);
    child.frame_body = child.owner = b.name;
    child.in_owner = Eigen::Isometry3d::Identity();
  }
}

// ---- masses ---------------------------------------------------------------------------------------

// A tensor the import turned or composed carries rounding that the file's numbers did not: what
// is left of an exact zero (4 ulps of the largest moment) becomes 0, and a degenerate tensor (a
// rod, a plate, two point masses), whose smallest principal moment or triangle margin rounding
// may have pushed below zero where the reader decides exactly, gets 16 ulps of the largest moment
// added to each principal moment (J + δE keeps J's axes; M moves by 1e-15 of itself).
void Importer::settle(Mat& inertia, Vec& c, const std::string& body) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double scale = inertia.cwiseAbs().maxCoeff();
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      if (std::abs(inertia(r, k)) <= 4 * eps * scale) inertia(r, k) = 0;
  const double cscale = c.cwiseAbs().maxCoeff();
  for (int k = 0; k < 3; ++k)
    if (std::abs(c(k)) <= 4 * eps * cscale) c(k) = 0;
  const Vec m = Eigen::SelfAdjointEigenSolver<Mat>(inertia, Eigen::EigenvaluesOnly).eigenvalues();
  if (scale > 0 && (m(0) < 16 * eps * scale || m(0) + m(1) - m(2) < 16 * eps * scale)) {
    inertia += 16 * eps * scale * Mat::Identity();
    notes_.push_back("body " + body + ": its turned or composed inertia is degenerate (a rod, a plate or point masses): " +
                     num(16 * eps * scale) + " kg m^2 added to each principal moment so that rounding keeps it physical");
  }
}

void Importer::compose_masses() {
  std::map<std::string, std::vector<const Link*>> by_owner;
  for (const auto& name : link_order_) {
    const Link& l = links_.at(name);
    if (l.massive) by_owner[l.owner].push_back(&l);
  }
  if (by_owner.count("world")) {
    double m = 0;
    std::string who;
    for (const Link* l : by_owner["world"]) m += l->mass, who += (who.empty() ? "'" : ", '") + comment(l->raw) + "'";
    notes_.push_back("the fixed base (" + who + ", " + num(m) + " kg) does not move: its mass does not enter the dynamics");
    by_owner.erase("world");
  }
  for (auto& body : bodies_) {
    auto it = by_owner.find(body.name);
    if (it == by_owner.end()) continue;
    double m = 0;
    Vec mc = Vec::Zero();
    std::vector<std::pair<Vec, Mat>> parts;  // centre and inertia in the owner's frame
    std::string from;
    for (const Link* l : it->second) {
      const Vec c = l->in_owner * l->com;
      const Mat r = l->in_owner.linear();
      parts.push_back({c, r * l->inertia * r.transpose()});
      m += l->mass;
      mc += l->mass * c;
      from += std::string(from.empty() ? "" : " + ") + "link '" + comment(l->raw) + "' <inertial> (" +
              where(l->inertial_line) + ")";
    }
    const Vec c = parts.size() == 1 ? parts[0].first : Vec(mc / m);  // one link: its own numbers, unrounded
    Mat inertia = Mat::Zero();
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const Vec d = parts[i].first - c;
      inertia += parts[i].second + it->second[i]->mass * (d.squaredNorm() * Mat::Identity() - d * d.transpose());
    }
    Vec cc = c;
    const bool as_written = parts.size() == 1 && !it->second[0]->rotated && it->second[0]->in_owner.isApprox(
                                                                                 Eigen::Isometry3d::Identity(), 0);
    if (!as_written) settle(inertia, cc, body.name);
    if (!std::isfinite(m) || !cc.allFinite() || !inertia.allFinite())
      throw ModelError({file_, it->second[0]->inertial_line, 0},
                       "body " + body.name + ": its composed mass properties overflow double");
    const std::string src = parts.size() > 1 ? "composed of " + from : from;
    MassParameters p;
    auto param = [&](const std::string& suffix, double value, const char* unit) {
      if (value == 0) return std::string("0");
      const std::string n = symbols_.take(body.name + suffix, nullptr, nullptr);
      parameters_.push_back("  " + n + ": {value: " + num(value) + ", unit: " + unit + ", source: " + quoted(src) + "}");
      return n;
    };
    p.mass = param("_m", m, "kg");
    const char* axes[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) p.com[k] = param(std::string("_c") + axes[k], cc(k), "m");
    const int rows[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    const char* names[6] = {"_Ixx", "_Iyy", "_Izz", "_Ixy", "_Ixz", "_Iyz"};
    for (int k = 0; k < 6; ++k) p.inertia[k] = param(names[k], inertia(rows[k][0], rows[k][1]), "kg m^2");
    masses_[body.name] = p;
  }
}

// ---- writing --------------------------------------------------------------------------------------

void Importer::write_parameters(std::ostringstream& y) {
  y << "parameters:\n";
  const Vec g(opt_.gravity[0], opt_.gravity[1], opt_.gravity[2]);
  if (g.norm() > 0)
    y << "  g: {value: " << num(g.norm()) << ", unit: m/s^2, source: \"gravity (mbsgen import; URDF has none)\"}\n";
  for (const auto& p : parameters_) y << p << "\n";
}

void Importer::write_coordinates(std::ostringstream& y) {
  y << "\ncoordinates:\n";
  for (const auto& [name, rest] : coordinates_) {
    const auto hash = rest.find("   #");
    y << "  - {name: " << name << ", unit: " << rest.substr(0, hash) << "}" << (hash == std::string::npos ? "" : rest.substr(hash))
      << "\n";
  }
}

void Importer::write_bodies(std::ostringstream& y) {
  y << "\nbodies:\n";
  for (const Body& b : bodies_) {
    y << "  # " << b.source << "\n";
    y << "  - name: " << b.name << "\n";
    if (b.parent != "world") y << "    parent: " << b.parent << "\n";
    if (b.translation != "[0, 0, 0]" && !b.translation.empty()) y << "    translation: " << b.translation << "\n";
    if (!b.rotation.empty()) y << "    " << b.rotation << "\n";
    auto it = masses_.find(b.name);
    if (it == masses_.end()) continue;
    const MassParameters& p = it->second;
    y << "    mass: " << p.mass << "\n";
    if (p.com != std::array<std::string, 3>{"0", "0", "0"}) y << "    com: " << list({p.com[0], p.com[1], p.com[2]}) << "\n";
    const char* keys[6] = {"xx", "yy", "zz", "xy", "xz", "yz"};
    std::vector<std::string> entries;
    for (int k = 0; k < 6; ++k)
      if (p.inertia[k] != "0") entries.push_back(std::string(keys[k]) + ": " + p.inertia[k]);
    if (!entries.empty()) {
      std::string s = "{";
      for (std::size_t i = 0; i < entries.size(); ++i) s += (i ? ", " : "") + entries[i];
      y << "    inertia: " << s << "}\n";
    }
  }
}

void Importer::write_forces(std::ostringstream& y) {
  std::vector<std::string> forces, inputs, constraints;
  const Vec g(opt_.gravity[0], opt_.gravity[1], opt_.gravity[2]);
  if (g.norm() > 0) {
    const Vec d = g / g.norm();
    auto comp = [&](int k) { return d(k) == 0 ? std::string("0") : d(k) == 1 ? "g" : d(k) == -1 ? "-g" : num(d(k)) + "*g"; };
    forces.push_back("{type: gravity, g: [" + comp(0) + ", " + comp(1) + ", " + comp(2) + "]}");
  }
  std::set<std::string> elastic(opt_.elastic.begin(), opt_.elastic.end());
  const bool all = elastic.count("all") > 0;
  for (const auto& name : joint_order_) {
    const Joint& j = joints_.at(name);
    if (j.coordinates.size() != 1) continue;
    const std::string& q = j.coordinates[0];
    const bool prismatic = j.type == "prismatic";
    if (j.damping > 0) {
      const std::string c = symbols_.take(q + "_damping", nullptr, nullptr);
      parameters_.push_back("  " + c + ": {value: " + num(j.damping) + ", unit: " + (prismatic ? "N s/m" : "N m s/rad") +
                            ", source: " + quoted("<dynamics damping> of joint '" + j.raw + "' (" + where(j.line) + ")") + "}");
      forces.push_back("{type: generalized, name: " + entities_.take(q + "_damper", nullptr, nullptr) + ", coordinate: " + q +
                       ", value: -" + c + "*" + q + "_dot, category: dampers}");
    }
    if (j.friction > 0)
      notes_.push_back("joint '" + comment(j.raw) + "': friction " + num(j.friction) +
                       " not imported (Coulomb friction has no linearization)");
    if (!j.mimic.empty()) {
      const Joint& m = joints_.at(j.mimic);
      std::string rhs = m.coordinates[0];
      if (j.multiplier != 1) rhs = num(j.multiplier) + "*" + rhs;
      if (j.offset != 0) rhs += (j.offset > 0 ? " + " : " - ") + num(std::abs(j.offset));
      const std::string constraint = entities_.take(q + "_mimic", nullptr, nullptr);
      constraints.push_back("{type: expression, name: " + constraint + ", expression: " + quoted(q + " - (" + rhs + ")") + "}");
      notes_.push_back("joint '" + comment(j.raw) + "' mimics '" + comment(j.mimic) + "': the constraint " + constraint);
      continue;
    }
    if (all || elastic.count(j.raw)) {
      const std::string k = symbols_.take("k_" + q, nullptr, nullptr), d = symbols_.take("d_" + q, nullptr, nullptr),
                        rest = symbols_.take(q + "_rest", nullptr, nullptr);
      const auto pose = opt_.pose.find(j.raw);
      parameters_.push_back("  " + k + ": {value: " + num(opt_.stiffness) + ", unit: " + (prismatic ? "N/m" : "N m/rad") +
                            ", source: \"joint stiffness (mbsgen import --elastic)\"}");
      parameters_.push_back("  " + d + ": {value: " + num(opt_.damping) + ", unit: " + (prismatic ? "N s/m" : "N m s/rad") +
                            ", source: \"joint damping (mbsgen import --elastic)\"}");
      parameters_.push_back("  " + rest + ": {value: " + num(pose == opt_.pose.end() ? 0.0 : pose->second) +
                            ", unit: " + (prismatic ? "m" : "rad") + ", source: \"the spring's rest (mbsgen import --pose)\"}");
      forces.push_back("{type: generalized, name: " + entities_.take(q + "_spring", nullptr, nullptr) + ", coordinate: " + q +
                       ", value: -" + k + "*(" + q + " - " + rest + "), category: springs}");
      forces.push_back("{type: generalized, name: " + entities_.take(q + "_joint_damper", nullptr, nullptr) +
                       ", coordinate: " + q + ", value: -" + d + "*" + q + "_dot, category: dampers}");
    }
    if (opt_.inputs) {
      const std::string u = symbols_.take((prismatic ? "f_" : "tau_") + q, nullptr, nullptr);
      inputs.push_back("{name: " + u + ", unit: " + (prismatic ? "N" : "N m") + "}");
      forces.push_back("{type: generalized, name: " + entities_.take(q + "_drive", nullptr, nullptr) + ", coordinate: " + q +
                       ", value: " + u + "}");
    }
  }
  if (!inputs.empty()) {
    y << "\ninputs:\n";
    for (const auto& i : inputs) y << "  - " << i << "\n";
  }
  write_bodies(y);
  if (!forces.empty()) {
    y << "\nforces:\n";
    for (const auto& f : forces) y << "  - " << f << "\n";
  }
  if (!constraints.empty()) {
    y << "\nconstraints:\n";
    for (const auto& c : constraints) y << "  - " << c << "\n";
    // The joints a mimic follows stay the independent ones (the linear model's coordinates).
    std::set<std::string> followers;
    for (const auto& name : joint_order_)
      if (!joints_.at(name).mimic.empty()) followers.insert(joints_.at(name).coordinates[0]);
    std::vector<std::string> independent;
    for (const auto& c : coordinates_)
      if (!followers.count(c.first)) independent.push_back(c.first);
    y << "independent_coordinates: " << list(independent) << "\n";
  }
}

void Importer::write_outputs(std::ostringstream& y) {
  std::vector<std::string> chosen = opt_.outputs;
  if (chosen.empty())
    for (const auto& name : link_order_)
      if (links_.at(name).children.empty() && name != root_) chosen.push_back(name);
  std::vector<std::string> markers, outputs;
  for (const auto& name : chosen) {
    const Link& l = links_.at(name);
    const std::string m = entities_.take(l.id + "_origin", nullptr, nullptr);
    if (!l.frame_body.empty()) {
      markers.push_back("{name: " + m + ", body: " + l.frame_body + "}");
    } else {
      std::string s = "{name: " + m + ", body: " + l.marker_body + ", position: [" + num(l.marker_pose.xyz.x()) + ", " +
                      num(l.marker_pose.xyz.y()) + ", " + num(l.marker_pose.xyz.z()) + "]";
      const auto rot = rpy_rotations(l.marker_pose.rpy);
      if (!rot.empty()) s += ", rotation: " + list(rot);
      markers.push_back(s + "}");
    }
    const char* axes[] = {"x", "y", "z"};
    const char* dirs[] = {"[1, 0, 0]", "[0, 1, 0]", "[0, 0, 1]"};
    for (int k = 0; k < 3; ++k)
      outputs.push_back("{name: " + entities_.take(l.id + "_" + axes[k], nullptr, nullptr) + ", type: position, marker: " + m +
                        ", direction: " + dirs[k] + ", unit: m}");
    for (int k = 0; k < 3; ++k)
      outputs.push_back("{name: " + entities_.take(l.id + "_v" + axes[k], nullptr, nullptr) + ", type: velocity, marker: " + m +
                        ", direction: " + dirs[k] + ", unit: m/s}");
  }
  if (!markers.empty()) {
    y << "\nmarkers:   # the origins of the links whose motion is an output\n";
    for (const auto& m : markers) y << "  - " << m << "\n";
    y << "\noutputs:\n";
    for (const auto& o : outputs) y << "  - " << o << "\n";
  }
  y << "\n# Linearized at the static equilibrium nearest the pose (Newton's method at run time).\noperating_point:\n"
    << "  type: equilibrium\n";
  std::vector<std::string> pose;
  for (const auto& name : joint_order_) {
    const Joint& j = joints_.at(name);
    auto it = opt_.pose.find(j.raw);
    if (it != opt_.pose.end() && j.coordinates.size() == 1 && it->second != 0)
      pose.push_back(j.coordinates[0] + ": " + num(it->second));
  }
  if (!pose.empty()) {
    std::string s = "{";
    for (std::size_t i = 0; i < pose.size(); ++i) s += (i ? ", " : "") + pose[i];
    y << "  position: " << s << "}\n";
  }
}

// The tree, checked here (urdfdom 3.0 does not): every joint's links exist, no link has two
// parents, one root, every link reached from it; at least one joint moves.
void Importer::check_tree() {
  std::map<std::string, std::string> parent_joint;
  for (const auto& name : joint_order_) {
    const Joint& j = joints_.at(name);
    const TiXmlElement* at = joint_elements_.at(name);
    for (const std::string* l : {&j.parent, &j.child})
      if (!links_.count(*l)) fail(at, "joint '" + comment(j.raw) + "': no link '" + comment(*l) + "'");
    auto [it, fresh] = parent_joint.emplace(j.child, name);
    if (!fresh)
      fail(at, "link '" + comment(j.child) + "' has two parents: joints '" + comment(it->second) + "' and '" +
                   comment(name) + "'");
  }
  std::vector<std::string> roots;
  for (const auto& name : link_order_)
    if (!parent_joint.count(name)) roots.push_back(name);
  if (roots.size() != 1)
    fail(doc_.RootElement(), roots.empty() ? "no root link: the joints form a cycle"
                                           : "two root links, '" + comment(roots[0]) + "' and '" + comment(roots[1]) + "'");
  root_ = roots[0];
  for (const auto& name : joint_order_) links_.at(joints_.at(name).parent).children.push_back(name);
  std::set<std::string> reached{root_};
  std::vector<std::string> stack{root_};
  while (!stack.empty()) {
    const std::string l = stack.back();
    stack.pop_back();
    for (const auto& j : links_.at(l).children)
      if (reached.insert(joints_.at(j).child).second) stack.push_back(joints_.at(j).child);
  }
  for (const auto& name : link_order_)
    if (!reached.count(name)) fail(doc_.RootElement()->FirstChildElement("link"), "link '" + comment(name) + "' is not connected to the root link '" + comment(root_) + "' (the joints form a cycle)");
  if (std::all_of(joint_order_.begin(), joint_order_.end(), [&](const std::string& n) { return joints_.at(n).type == "fixed"; }) &&
      !opt_.floating_base)
    fail(doc_.RootElement(), "no joint moves (every joint is fixed): nothing to model");
}

void Importer::check_mimics_and_options() {
  auto scalar = [](const std::string& t) { return t == "revolute" || t == "continuous" || t == "prismatic"; };
  for (const auto& name : joint_order_) {
    const Joint& j = joints_.at(name);
    if (j.mimic.empty()) continue;
    auto m = joints_.find(j.mimic);
    const TiXmlElement* at = joint_elements_.at(name)->FirstChildElement("mimic");
    if (m == joints_.end()) fail(at, "joint '" + comment(j.raw) + "' mimics '" + comment(j.mimic) + "', which is not a joint of the file");
    if (!scalar(j.type) || !scalar(m->second.type) || !m->second.mimic.empty() || m->first == name)
      fail(at, "joint '" + comment(j.raw) + "' mimics '" + comment(j.mimic) +
                   "': a mimic couples two revolute, continuous or prismatic joints, and not a mimic of a mimic");
  }
  auto refuse = [](const std::string& what) { throw UrdfOptionError(what); };
  for (const auto& e : opt_.elastic) {
    if (e == "all") continue;
    auto j = joints_.find(e);
    if (j == joints_.end()) refuse("--elastic: no joint '" + comment(e) + "' in the file");
    if (!scalar(j->second.type) || !j->second.mimic.empty())
      refuse("--elastic: joint '" + comment(e) + "' is " + (j->second.mimic.empty() ? j->second.type : "a mimic") +
             ": only revolute, continuous and prismatic joints that are not mimics get a spring");
  }
  for (const auto& [name, v] : opt_.pose) {
    auto j = joints_.find(name);
    if (j == joints_.end()) refuse("--pose: no joint '" + comment(name) + "' in the file");
    if (!scalar(j->second.type)) refuse("--pose: joint '" + comment(name) + "' is " + j->second.type + ", not one angle or slide");
    if (!std::isfinite(v)) refuse("--pose: the value of '" + comment(name) + "' is not finite");
  }
  for (const auto& o : opt_.outputs)
    if (!links_.count(o)) refuse("--output: no link '" + comment(o) + "' in the file");
  for (double g : opt_.gravity)
    if (!std::isfinite(g)) refuse("--gravity: not a finite vector");
  if (!(opt_.stiffness > 0) || !std::isfinite(opt_.stiffness) || !(opt_.damping >= 0) || !std::isfinite(opt_.damping))
    refuse("--stiffness must be positive and --damping nonnegative (finite)");
}

UrdfImport Importer::run() {
  parse_xml();
  check_tree();  // first: urdfdom 3.0 leaks the links of a cycle it was given
  check_with_urdfdom();
  check_mimics_and_options();
  symbols_.reserve("g");  // gravity's magnitude
  for (const auto& name : link_order_) links_.at(name).id = entities_.take(name, &notes_, "link");
  place_root();
  // Depth first from the root, each joint's children in the file's order (no recursion: a chain
  // of thousands of links is a loop, not a stack).
  std::vector<std::string> stack(links_.at(root_).children.rbegin(), links_.at(root_).children.rend());
  while (!stack.empty()) {
    const std::string j = stack.back();
    stack.pop_back();
    place(j);
    const auto& next = links_.at(joints_.at(j).child).children;
    stack.insert(stack.end(), next.rbegin(), next.rend());
  }
  compose_masses();
  std::string model = robot_;
  for (auto& c : model) c = std::isalnum(static_cast<unsigned char>(c)) && static_cast<unsigned char>(c) < 0x80 ? c : '_';
  if (model.empty() || !std::isalpha(static_cast<unsigned char>(model[0]))) model = "robot_" + model;
  if (reserved_identifier(model)) model += "_robot";
  std::ostringstream body;
  write_outputs(body);  // names markers and outputs (after the bodies' names, before writing them)
  std::ostringstream y;
  write_forces(y);  // parameters of joints come into being here
  std::ostringstream head;
  head << "# Generated by mbsgen import from " << comment(file_) << " (robot '" << comment(robot_) << "').\n"
       << "# Every number is the file's, or composed of its numbers where a fixed joint lumps links; a source\n"
       << "# names the lines it came from. Lengths m, masses kg, inertias\n"
       << "# kg m^2 about the centre of mass in the body (link) frame, angles rad.\n";
  for (const auto& n : notes_) head << "# note: " << n << "\n";
  if (!skipped_.empty()) {
    head << "# not imported:";
    for (const auto& [tag, n] : skipped_) head << " " << n << " " << tag;
    head << "\n";
  }
  head << "model: " << model << "\n\n";
  write_parameters(head);
  write_coordinates(head);
  UrdfImport result;
  result.yaml = head.str() + y.str() + body.str();
  result.yaml += urdf_import_checksum(result.yaml);
  result.notes = notes_;
  if (!skipped_.empty()) {
    std::string s = "not imported (no effect on the dynamics):";
    for (const auto& [tag, n] : skipped_) s += " " + std::to_string(n) + " " + tag;
    result.notes.push_back(s);
  }
  return result;
}

}  // namespace

UrdfImport import_urdf_string(const std::string& text, const std::string& file_name, const UrdfImportOptions& options) {
  return Importer(text, file_name, options).run();
}

#endif

}  // namespace mbsgen
