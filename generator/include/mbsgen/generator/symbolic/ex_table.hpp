// A hash table keyed by GiNaC expressions (structural equality, GiNaC's hash), with open
// addressing: the generator's memos (canonical keys, intermediates by symbol) are looked up
// millions of times for a large model, and a node-based std::unordered_map costs three cache
// misses per lookup (bucket, node, key) where this costs one or two (slot, and the stored key
// only when it is a different object of the same hash: the slot keeps the key's address).
#pragma once

#include <ginac/ginac.h>

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace mbsgen {

template <class V>
class ExTable {
 public:
  ExTable() { slots_.resize(kMinSlots); }

  /// The value stored for e, or nullptr.
  V* find(const GiNaC::ex& e) { return const_cast<V*>(static_cast<const ExTable&>(*this).find(e)); }
  const V* find(const GiNaC::ex& e) const {
    const GiNaC::basic* object = &GiNaC::ex_to<GiNaC::basic>(e);
    const unsigned hash = e.gethash();
    for (std::size_t i = start(hash);; i = (i + 1) & (slots_.size() - 1)) {
      const Slot& s = slots_[i];
      if (!s.object) return nullptr;
      if (s.hash == hash && (s.object == object || s.key.is_equal(e))) return &s.value;
    }
  }

  /// Stores v for e, which must not be present.
  void insert(const GiNaC::ex& e, V v) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    place(e, e.gethash(), std::move(v));
    ++size_;
  }

  /// Stores v for e unless e is present (as std::unordered_map::emplace); true when stored.
  bool emplace(const GiNaC::ex& e, V v) {
    if (find(e)) return false;
    insert(e, std::move(v));
    return true;
  }
  /// The value stored for e, stored as V{} first when e is absent.
  V& operator[](const GiNaC::ex& e) {
    if (V* v = find(e)) return *v;
    insert(e, V{});
    return *find(e);
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  /// Forgets every entry (and releases the expressions), keeping the slots.
  void clear() {
    for (Slot& s : slots_) s = Slot();
    size_ = 0;
  }

  void swap(ExTable& other) noexcept {
    slots_.swap(other.slots_);
    std::swap(size_, other.size_);
  }

 private:
  static constexpr std::size_t kMinSlots = 16;
  struct Slot {
    const GiNaC::basic* object = nullptr;  // the key's address; null: empty
    unsigned hash = 0;
    GiNaC::ex key;  // holds the object, so that no other one takes its address meanwhile
    V value{};
  };

  std::size_t start(unsigned hash) const {
    // Fibonacci hashing: GiNaC's hashes of neighbouring symbols differ in few bits.
    return static_cast<std::size_t>((std::uint64_t{hash} * 0x9e3779b97f4a7c15ULL) >> 20) & (slots_.size() - 1);
  }

  void place(const GiNaC::ex& e, unsigned hash, V v) {
    std::size_t i = start(hash);
    while (slots_[i].object) i = (i + 1) & (slots_.size() - 1);
    slots_[i] = Slot{&GiNaC::ex_to<GiNaC::basic>(e), hash, e, std::move(v)};
  }

  void grow() {
    std::vector<Slot> old(2 * slots_.size());
    old.swap(slots_);
    for (Slot& s : old)
      if (s.object) place(s.key, s.hash, std::move(s.value));
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

}  // namespace mbsgen
