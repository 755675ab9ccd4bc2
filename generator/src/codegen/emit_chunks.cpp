#include "codegen/emit_chunks.hpp"

#include <algorithm>
#include <sstream>

namespace mbsgen::detail {

namespace {

// The chunk of each statement: a new chunk starts once the current one has max_operations.
std::vector<std::size_t> assign_chunks(const std::vector<PrintedStatement>& s, std::size_t max_operations,
                                       std::vector<std::size_t>& operations) {
  std::vector<std::size_t> chunk(s.size(), 0);
  operations.assign(1, 0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (operations.back() >= max_operations) operations.push_back(0);
    chunk[i] = operations.size() - 1;
    operations.back() += s[i].operations;
  }
  return chunk;
}

constexpr std::size_t kNoSlot = static_cast<std::size_t>(-1);

// The statements in the order `order` (a permutation of their indices), with what each reads
// renumbered to match.
std::vector<PrintedStatement> permuted(const std::vector<PrintedStatement>& s, const std::vector<std::size_t>& order) {
  std::vector<std::size_t> position(s.size());
  for (std::size_t k = 0; k < order.size(); ++k) position[order[k]] = k;
  std::vector<PrintedStatement> out;
  out.reserve(s.size());
  for (std::size_t i : order) {
    out.push_back(s[i]);
    for (auto& r : out.back().reads) r = position[r];
  }
  return out;
}

// The statements in the order the outputs demand them: each output (in its original order) right
// after the locals it reads that are not yet computed, those in their original order, depth
// first. Values are then computed near their use, so that few cross a part's boundary (the
// emitter's order defines every intermediate before the first output: the 40-coordinate chain's
// mass matrix loaded 1,866 values from the workspace and stored 1,272 in parts of 14,742
// operations, 20 % more instructions). The order of independent statements does not change a
// single value.
std::vector<PrintedStatement> demand_order(const std::vector<PrintedStatement>& s, std::vector<std::size_t>& original) {
  std::vector<char> placed(s.size(), 0);
  std::vector<std::size_t> order;
  order.reserve(s.size());
  for (std::size_t root = 0; root < s.size(); ++root) {
    if (!s[root].defines.empty() && !s[root].needed_after) continue;  // a local: placed on demand
    // Post-order walk from the output, children in their original (definition) order.
    std::vector<std::pair<std::size_t, std::size_t>> stack{{root, 0}};
    while (!stack.empty()) {
      auto& [i, next] = stack.back();
      if (placed[i]) {
        stack.pop_back();
        continue;
      }
      if (next < s[i].reads.size()) {
        const std::size_t child = s[i].reads[next++];
        if (!placed[child]) stack.push_back({child, 0});
        continue;
      }
      placed[i] = 1;
      order.push_back(i);
      stack.pop_back();
    }
  }
  for (std::size_t i = 0; i < s.size(); ++i)  // locals no output reads (none in practice)
    if (!placed[i]) order.push_back(i);
  original = order;
  return permuted(s, order);
}

// Within each part, the statements that define locals in their original (definition) order and
// each output right after the last of them it reads, as in a whole kernel (emit.cpp, whole_body):
// the demand order decides which part computes what (and so what crosses parts), this order how
// a part computes it. The 10-link chain's linear kernel (11,589 operations in 5 parts) took
// 1.34× the time of its whole form in the demand order.
std::vector<PrintedStatement> order_within_parts(const std::vector<PrintedStatement>& s, const std::vector<std::size_t>& chunk,
                                                 const std::vector<std::size_t>& original) {
  std::vector<std::size_t> order;
  order.reserve(s.size());
  for (std::size_t begin = 0; begin < s.size();) {
    std::size_t end = begin;
    while (end < s.size() && chunk[end] == chunk[begin]) ++end;
    std::vector<std::size_t> locals, outputs;
    for (std::size_t i = begin; i < end; ++i) (s[i].defines.empty() ? outputs : locals).push_back(i);
    std::sort(locals.begin(), locals.end(), [&](std::size_t a, std::size_t b) { return original[a] < original[b]; });
    // after[k + 1]: the outputs whose last read in this part is locals[k]; after[0]: none read here.
    std::vector<std::size_t> rank(end - begin, 0);
    for (std::size_t k = 0; k < locals.size(); ++k) rank[locals[k] - begin] = k + 1;
    std::vector<std::vector<std::size_t>> after(locals.size() + 1);
    for (std::size_t o : outputs) {
      std::size_t last = 0;
      for (std::size_t r : s[o].reads)
        if (r >= begin && r < end) last = std::max(last, rank[r - begin]);
      after[last].push_back(o);
    }
    for (std::size_t o : after[0]) order.push_back(o);
    for (std::size_t k = 0; k < locals.size(); ++k) {
      order.push_back(locals[k]);
      for (std::size_t o : after[k + 1]) order.push_back(o);
    }
    begin = end;
  }
  return permuted(s, order);
}

}  // namespace

ChunkedBody chunk_body(const std::string& qualifier, const std::string& name, const std::string& parameters,
                       const std::string& arguments, const std::vector<PrintedStatement>& statements,
                       std::size_t max_operations) {
  std::vector<std::size_t> original;
  const std::vector<PrintedStatement> demanded = demand_order(statements, original);
  ChunkedBody out;
  const std::vector<std::size_t> chunk = assign_chunks(demanded, max_operations, out.operations);
  const std::vector<PrintedStatement> s = order_within_parts(demanded, chunk, original);
  const std::size_t chunks = out.operations.size();

  // The last chunk that reads each local defined in an earlier one (chunks: read after them all).
  std::vector<std::size_t> last_read(s.size(), kNoSlot);
  std::vector<std::vector<std::size_t>> loads(chunks);
  for (std::size_t j = 0; j < s.size(); ++j)
    for (std::size_t i : s[j].reads)
      if (chunk[i] < chunk[j]) {
        if (last_read[i] == kNoSlot || last_read[i] < chunk[j]) last_read[i] = chunk[j];
        loads[chunk[j]].push_back(i);
      }
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s[i].needed_after) last_read[i] = chunks;
  for (auto& l : loads) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }

  // Slots: a value's slot is free again once its last reader has loaded it (at that chunk's top,
  // before the chunk stores anything).
  std::vector<std::size_t> slot(s.size(), kNoSlot), free_slots;
  std::vector<std::vector<std::size_t>> release(chunks + 1);
  std::size_t i = 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    for (std::size_t k : release[c]) free_slots.push_back(k);
    std::sort(free_slots.begin(), free_slots.end(), std::greater<>());  // lowest slot first
    for (; i < s.size() && chunk[i] == c; ++i) {
      if (last_read[i] == kNoSlot) continue;
      if (free_slots.empty()) {
        slot[i] = out.workspace++;
      } else {
        slot[i] = free_slots.back();
        free_slots.pop_back();
      }
      release[last_read[i]].push_back(slot[i]);
    }
  }

  std::ostringstream unused;
  for (std::size_t a = 0, b = 0; a <= arguments.size(); ++a)
    if (a == arguments.size() || arguments[a] == ',') {
      std::string arg = arguments.substr(b, a - b);
      arg.erase(0, arg.find_first_not_of(' '));
      unused << "  (void)" << arg << ";\n";
      b = a + 1;
    }
  const std::string signature_tail = "(" + parameters + ", double* w)";
  for (std::size_t c = 0, j = 0; c < chunks; ++c) {
    const std::string fn = name + "_" + std::to_string(c);
    out.declarations += "void " + fn + signature_tail + ";\n";
    std::ostringstream d;
    d << "void " << fn << signature_tail << " {\n" << unused.str();
    for (std::size_t k : loads[c]) d << "  const double " << s[k].defines << " = w[" << slot[k] << "];\n";
    for (; j < s.size() && chunk[j] == c; ++j) {
      d << s[j].code;
      if (slot[j] != kNoSlot) d << "  w[" << slot[j] << "] = " << s[j].defines << ";\n";
    }
    d << "}\n";
    out.definitions.push_back(d.str());
  }

  std::ostringstream calls;
  calls << "  // " << chunks << " parts of about " << max_operations << " operations each (emit_chunks.hpp); w: "
        << "the values that cross from one part to a later one.\n";
  calls << "  double w[" << std::max<std::size_t>(out.workspace, 1) << "];\n";
  for (std::size_t c = 0; c < chunks; ++c) calls << "  " << qualifier << name << "_" << c << "(" << arguments << ", w);\n";
  for (std::size_t k = 0; k < s.size(); ++k)
    if (s[k].needed_after) calls << "  const double " << s[k].defines << " = w[" << slot[k] << "];\n";
  out.calls = calls.str();
  return out;
}

}  // namespace mbsgen::detail
