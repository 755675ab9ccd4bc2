// Fast type tests of GiNaC expressions for the generator's inner loops.
//
// GiNaC::is_a<T> is a dynamic_cast. libstdc++ compares type_info objects by name (strcmp) when
// their addresses differ, and a cast that fails walks the class hierarchy doing so at every
// level: the type tests of canonical keys, of the program's walks, of the sample evaluator and of
// CSE were a tenth of the 40-link spatial chain's generation (perf, issue 17).
//
// isa<T> compares the address of the node's type_info with those of GiNaC's node classes first.
// An address that matches is that exact class, whose answer for every T is known at compile time.
// One that matches none (another class, a subclass such as realsymbol, a type_info duplicated
// across shared objects) goes to GiNaC::is_a: the answer is GiNaC's in every case, only faster for
// the usual nodes.
#pragma once

#include <ginac/ginac.h>

#include <type_traits>
#include <typeinfo>

namespace mbsgen {

template <class T>
bool isa(const GiNaC::ex& e) {
  const std::type_info& t = typeid(GiNaC::ex_to<GiNaC::basic>(e));
  if (&t == &typeid(GiNaC::symbol)) return std::is_base_of_v<T, GiNaC::symbol>;
  if (&t == &typeid(GiNaC::numeric)) return std::is_base_of_v<T, GiNaC::numeric>;
  if (&t == &typeid(GiNaC::mul)) return std::is_base_of_v<T, GiNaC::mul>;
  if (&t == &typeid(GiNaC::add)) return std::is_base_of_v<T, GiNaC::add>;
  if (&t == &typeid(GiNaC::power)) return std::is_base_of_v<T, GiNaC::power>;
  if (&t == &typeid(GiNaC::function)) return std::is_base_of_v<T, GiNaC::function>;
  return GiNaC::is_a<T>(e);
}

}  // namespace mbsgen
