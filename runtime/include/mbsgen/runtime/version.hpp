// The runtime's version: the project's (CMakeLists.txt `project(mbsgen VERSION …)`), the same as
// the generator's kGeneratorVersion; tests check both against the project version.
#pragma once

namespace mbsgen {

/// Version of the mbsgen runtime, printed by `--version` of `mbsgen linear` and the solvers.
inline constexpr const char* kRuntimeVersion = "0.1.0";

}  // namespace mbsgen
