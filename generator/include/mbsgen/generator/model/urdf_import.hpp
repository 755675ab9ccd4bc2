// Importing a robot description in URDF (the Unified Robot Description Format of ROS) as an mbsgen
// model (docs/urdf.md). The file is parsed and checked by urdfdom (the tree, joint types, mimic,
// dynamics, limits); its XML is read again with line numbers so that every number keeps the text
// it was written with and every message can point at its element. The result is a model file in
// the YAML format of docs/model-format.md, commented with where each number came from, which
// read_model_string() turns into a Model like any other.
//
// What becomes what:
//   link with a moving joint      a body (mass, centre of mass, inertia rotated from the
//                                 <inertial> frame into the link frame), placed by the joint's
//                                 <origin> (translation xyz, rotations z-y-x of rpy) and moved by
//                                 its coordinate(s)
//   revolute, continuous          one angle about the axis; prismatic: one slide along it;
//   floating                      x, y, z and yaw, pitch, roll (z-y-x); planar: two slides in the
//                                 plane and the angle about its normal (a normal along x, y or z)
//   fixed                         the child's mass lumped into the nearest moving ancestor (mass,
//                                 centre and inertia composed by the parallel-axis theorem); its
//                                 frame a massless body (when links hang from it) or a marker
//   <mimic>                       an expression constraint q − (multiplier q_master + offset) = 0
//   <dynamics damping>            a joint damper (category dampers); friction is not imported
//                                 (Coulomb friction has no linearization), said in a note
//   <limit>                       kept as a comment at the coordinate
// Options add gravity, joint springs (series elastic joints), joint torque inputs and outputs at
// links. Whatever the file holds that is not imported (visual, collision, transmission, gazebo,
// sensors, materials, calibration, safety controllers) is listed in the notes, once.
#pragma once

#include "mbsgen/generator/model/model.hpp"

#include <array>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbsgen {

struct UrdfImportOptions {
  /// `floating`: the root link gets six coordinates (x, y, z, yaw, pitch, roll) against the world;
  /// `fixed` (default): the root link is the world, as URDF means it.
  bool floating_base = false;
  /// Gravity in the world frame, m/s² (URDF has none; ROS's convention is −z).
  std::array<double, 3> gravity{0, 0, -9.81};
  /// Joints that get a joint spring and damper (series elastic joints): names, or "all" for every
  /// revolute, continuous and prismatic joint that is not a mimic.
  std::vector<std::string> elastic;
  double stiffness = 1e4;  ///< of each elastic joint, N m/rad (N/m for a prismatic one)
  double damping = 10;     ///< of each elastic joint, N m s/rad (N s/m)
  /// Links whose origins become outputs (position and velocity, world frame); empty: the leaves.
  std::vector<std::string> outputs;
  /// Joint values of the pose (the operating point's guess and the springs' rest); others 0.
  std::map<std::string, double> pose;
  /// A torque (force) input at every actuated joint: revolute, continuous, prismatic, no mimic.
  bool inputs = true;
};

/// An option that names what the file does not have, or asks what cannot be (exit 2 on the
/// command line: a usage error, not a bad file).
class UrdfOptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct UrdfImport {
  std::string yaml;                ///< the model file
  std::vector<std::string> notes;  ///< what was not imported or was changed, one line each
};

/// Whether `path` names a URDF file (it ends in ".urdf", any case).
bool is_urdf_path(const std::string& path);

/// Imports the URDF text; `file_name` is used in messages and comments only. Throws ModelError
/// (FILE:LINE:COL) for malformed XML or elements nested deeper than 64, what urdfdom refuses (at
/// the element it names when it names one), a link with two parents, a cycle, a link not
/// connected to the root, a file where nothing moves, numbers that are not finite, a negative
/// mass, damping or friction, a non-physical inertia or a zero mass with a nonzero inertia (at
/// the link), a mimic of an unknown, non-scalar or mimic joint, a planar joint whose normal is not
/// along an axis; UrdfOptionError for options naming what the file lacks. ModelError at the file
/// name when the build has no URDF support (urdfdom). The text ends with a line holding a
/// checksum of the rest (`urdf_import_checksum`), by which mbsgen import knows a file it wrote
/// and that nobody edited since.
UrdfImport import_urdf_string(const std::string& text, const std::string& file_name,
                              const UrdfImportOptions& options = {});

/// The checksum line mbsgen import ends its model file with, for `text` (everything before it).
std::string urdf_import_checksum(const std::string& text);

/// import_urdf_string of the file's text (read as read_model_text reads a model file).
UrdfImport import_urdf_file(const std::string& path, const UrdfImportOptions& options = {});

}  // namespace mbsgen
