// Exception hierarchy of the mbsgen runtime (STYLE.md guideline 9: exceptions with context for
// bad input; the command-line tool maps them to exit codes).
#pragma once

#include <stdexcept>
#include <string>

namespace mbsgen {

/// Base of every exception the runtime throws for bad input or a failed computation.
/// The message names the function that detected the problem and the offending sizes or values.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Matrix or vector dimensions that do not fit together (e.g. M is 3x3 and K is 3x4).
class DimensionError : public Error {
 public:
  using Error::Error;
};

/// A NaN or an infinity in input data.
class NonFiniteError : public Error {
 public:
  using Error::Error;
};

/// A system that cannot be solved as asked: a singular mass matrix where an invertible one is
/// required, excitation exactly at an undamped resonance (when the caller asked for an error rather
/// than a flag), a numerically singular Jacobian in Newton's method.
class SingularSystemError : public Error {
 public:
  using Error::Error;
};

/// A result that exists but cannot be computed to useful accuracy by the requested method (e.g.
/// modal superposition with an ill-conditioned eigenvector matrix).
class IllConditionedError : public Error {
 public:
  using Error::Error;
};

/// An iteration (Newton's method for static equilibrium) that did not converge.
class ConvergenceError : public Error {
 public:
  using Error::Error;
};

/// Malformed input file (Matrix Market); the message carries file:line.
class ParseError : public Error {
 public:
  using Error::Error;
};

/// A LAPACK routine reported an error (illegal argument or failure to converge).
class LapackError : public Error {
 public:
  using Error::Error;
};

}  // namespace mbsgen
