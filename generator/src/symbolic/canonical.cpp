#include "mbsgen/generator/symbolic/canonical.hpp"

#include "symbolic/type_test.hpp"

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace mbsgen {

using GiNaC::ex;
using GiNaC::ex_to;

namespace {

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  // splitmix64 finaliser over the running hash
  std::uint64_t z = h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t text(std::uint64_t tag, const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL ^ tag;  // FNV-1a
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return mix(tag, h);
}

std::string to_text(const ex& e) {
  std::ostringstream s;
  s << e;
  return s.str();
}

bool commutative(const ex& e) { return isa<GiNaC::add>(e) || isa<GiNaC::mul>(e); }

}  // namespace

bool odd_function(const std::string& name) {
  static const std::set<std::string> odd = {"sin", "tan", "asin", "atan", "sinh", "tanh", "asinh", "atanh"};
  return odd.count(name) > 0;
}

bool even_function(const std::string& name) {
  static const std::set<std::string> even = {"cos", "cosh", "abs"};
  return even.count(name) > 0;
}

CanonicalOrder::CanonicalOrder(std::size_t memo_capacity) : capacity_(std::max<std::size_t>(memo_capacity, 1)) {}

void CanonicalOrder::set_sign(const ex& s, int sign) {
  if (!isa<GiNaC::symbol>(s)) throw std::logic_error("mbsgen::CanonicalOrder::set_sign: not a symbol");
  if (const Signed* old = signs_.find(s)) {
    if (old->sign != sign)
      throw std::logic_error("mbsgen::CanonicalOrder::set_sign: sign of " +
                             ex_to<GiNaC::symbol>(s).get_name() + " already used");
    return;
  }
  signs_.insert(s, Signed{text(1, ex_to<GiNaC::symbol>(s).get_name()), sign});
}

void CanonicalOrder::remember(const ex& e, Signed r) {
  if (current_.size() >= capacity_) {
    // A new generation: what the last two did not use again is forgotten (a key computed again
    // is the same key).
    previous_.swap(current_);
    current_.clear();
  }
  current_.insert(e, r);
}

CanonicalOrder::Signed CanonicalOrder::signed_key(const ex& e) {
  if (isa<GiNaC::symbol>(e)) {
    if (const Signed* r = signs_.find(e)) return *r;
    return {text(1, ex_to<GiNaC::symbol>(e).get_name()), 1};
  }
  if (const Signed* r = current_.find(e)) return *r;
  if (const Signed* r = previous_.find(e)) {
    const Signed copy = *r;  // remember() may clear previous_
    remember(e, copy);
    return copy;
  }
  const Signed r = compute(e);
  remember(e, r);
  return r;
}

CanonicalOrder::Signed CanonicalOrder::compute(const ex& e) {
  Signed r{0, 1};
  if (isa<GiNaC::numeric>(e)) {
    GiNaC::numeric n = ex_to<GiNaC::numeric>(e);
    if (n.is_real() && n.is_negative()) {
      r.sign = -1;
      n = -n;
    }
    r.key = text(2, to_text(n));
  } else if (isa<GiNaC::constant>(e)) {
    r.key = text(2, to_text(e));
  } else if (isa<GiNaC::add>(e)) {
    std::vector<std::pair<std::uint64_t, int>> terms;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      Signed t = signed_key(e.op(i));
      terms.push_back({t.key, t.sign});
    }
    std::sort(terms.begin(), terms.end());
    r.sign = terms.empty() ? 1 : terms.front().second;
    r.key = 3;
    for (const auto& [k, s] : terms) r.key = mix(mix(r.key, k), static_cast<std::uint64_t>(s * r.sign + 1));
  } else if (isa<GiNaC::mul>(e)) {
    std::vector<std::uint64_t> factors;
    for (std::size_t i = 0; i < e.nops(); ++i) {
      const ex& f = e.op(i);
      Signed t = signed_key(f);
      r.sign *= t.sign;
      if (isa<GiNaC::numeric>(f) && (f.is_equal(1) || f.is_equal(-1))) continue;
      factors.push_back(t.key);
    }
    std::sort(factors.begin(), factors.end());
    if (factors.size() == 1) {
      r.key = factors.front();  // ±x has the key of x
    } else {
      r.key = 4;
      for (std::uint64_t k : factors) r.key = mix(r.key, k);
    }
  } else if (isa<GiNaC::power>(e)) {
    Signed b = signed_key(e.op(0));
    Signed x = signed_key(e.op(1));
    r.key = mix(mix(5, b.key), mix(x.key, static_cast<std::uint64_t>(x.sign + 1)));
    const ex& n = e.op(1);
    if (isa<GiNaC::numeric>(n) && ex_to<GiNaC::numeric>(n).is_integer()) {
      if (ex_to<GiNaC::numeric>(n).is_odd()) r.sign = b.sign;
    } else {
      r.key = mix(r.key, static_cast<std::uint64_t>(b.sign + 1));  // the base's sign matters
    }
  } else if (isa<GiNaC::function>(e)) {
    const std::string name = ex_to<GiNaC::function>(e).get_name();
    r.key = text(6, name);
    if (e.nops() == 1 && (odd_function(name) || even_function(name))) {
      Signed a = signed_key(e.op(0));
      r.key = mix(r.key, a.key);
      if (odd_function(name)) r.sign = a.sign;
    } else {
      for (std::size_t i = 0; i < e.nops(); ++i) {
        Signed a = signed_key(e.op(i));
        r.key = mix(mix(r.key, a.key), static_cast<std::uint64_t>(a.sign + 1));
      }
    }
  } else {
    r.key = text(7, ex_to<GiNaC::basic>(e).class_name());
    for (std::size_t i = 0; i < e.nops(); ++i) {
      Signed a = signed_key(e.op(i));
      r.key = mix(mix(r.key, a.key), static_cast<std::uint64_t>(a.sign + 1));
    }
  }
  return r;
}

bool CanonicalOrder::less(const ex& a, const ex& b) {
  const std::uint64_t ka = key(a), kb = key(b);
  if (ka != kb) return ka < kb;
  return a.compare(b) < 0;
}

std::vector<ex> CanonicalOrder::operands(const ex& e) {
  const std::size_t n = e.nops();
  std::vector<ex> ops;
  ops.reserve(n);
  if (!commutative(e)) {
    for (std::size_t i = 0; i < n; ++i) ops.push_back(e.op(i));
    return ops;
  }
  // The order of less(), with each operand's key looked up once rather than at every comparison.
  std::vector<std::pair<std::uint64_t, ex>> keyed;
  keyed.reserve(n);
  for (std::size_t i = 0; i < n; ++i) keyed.emplace_back(key(e.op(i)), e.op(i));
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second.compare(b.second) < 0;
  });
  for (auto& k : keyed) ops.push_back(std::move(k.second));
  return ops;
}

}  // namespace mbsgen
