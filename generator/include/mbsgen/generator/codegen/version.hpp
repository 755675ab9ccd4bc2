// The generator's version (a header of its own: the `mbsgen` launcher, which links no GiNaC,
// keys the cache with it).
#pragma once

namespace mbsgen {

inline constexpr const char* kGeneratorVersion = "0.1.0";

}  // namespace mbsgen
