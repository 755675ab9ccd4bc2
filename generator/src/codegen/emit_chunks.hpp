// Splitting a long kernel body into functions of bounded size (issue 17 §1), internal to emit.
//
// A compiler's optimiser is superlinear in the size of a function: the 60-coordinate chain's
// `linear` kernel, one function of 122,525 operations, took GCC -O2 minutes and gigabytes. Cut
// into functions of about EmitOptions::chunk_operations each, the cost per operation is that of a small
// function, and the functions can go to several translation units compiled in parallel.
//
// A chunk is a run of consecutive statements. A temporary defined in one chunk and read in a
// later one travels through a workspace array w that the kernel keeps on its stack: stored after
// its definition, loaded into a local at the top of each later chunk that reads it. Slots are
// reused once their value's last reader has loaded it, so w holds only the values live across a
// chunk boundary.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace mbsgen::detail {

/// One printed statement of a kernel body.
struct PrintedStatement {
  std::string code;        ///< "  const double t5 = …;\n" or "  M[3] = …;\n"
  std::size_t operations;  ///< operations counted in code
  std::string defines;     ///< the C++ name of the local it defines ("" for an output entry)
  std::vector<std::size_t> reads;  ///< statements (defining locals) whose values it reads
  bool needed_after = false;  ///< its local is read by the kernel after the chunks (op values)
};

/// A kernel body cut into chunk functions.
struct ChunkedBody {
  std::vector<std::string> definitions;  ///< one function definition per chunk
  std::vector<std::size_t> operations;   ///< operations per chunk
  std::string declarations;              ///< their declarations
  std::string calls;  ///< the kernel's body: the workspace, the calls, loads of needed_after locals
  std::size_t workspace = 0;  ///< doubles in w
};

/// Cuts statements into chunks of about max_operations. name: the chunk functions' prefix
/// (name_0, name_1, …), declared and defined in a namespace whose qualifier ("ns::") the calls
/// use; parameters: the kernel's parameter list ("const double* y, double* M"); arguments: its
/// argument names ("y, M").
ChunkedBody chunk_body(const std::string& qualifier, const std::string& name, const std::string& parameters,
                       const std::string& arguments, const std::vector<PrintedStatement>& statements,
                       std::size_t max_operations);

}  // namespace mbsgen::detail
