#pragma once
/// \file
/// The exception hierarchy of tbs. Messages say what was wrong, where (file, line, element)
/// and, where possible, what to do about it. The `tbs` command maps each class to an exit code.
///
/// Each public function documents the tbs exceptions it throws (`\throw`) or that it throws
/// none. Any function that allocates may also throw std::bad_alloc; "Throws nothing" means
/// not even that.

#include <stdexcept>
#include <string>

namespace tbs {

/// Base of every exception tbs throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input (a file, a point, a spline) violates a documented requirement.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

/// A file could not be opened, read or written.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A numerical solver failed (a bug or a pathological input; never "poor fit quality").
class SolverError : public Error {
 public:
  using Error::Error;
};

/// The caller asked the work to stop (FitOptions::stop): not a failure, nothing is returned.
class Cancelled : public Error {
 public:
  using Error::Error;
};

/// A parameter point lies outside the spline's domain.
class OutsideDomain : public InvalidInput {
 public:
  using InvalidInput::InvalidInput;
};

}  // namespace tbs
