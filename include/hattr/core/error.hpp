#pragma once
/// Error policy (see ../shared/STYLE.md and docs/architecture.md):
/// - setup and offline code throws exceptions derived from hattr::Error;
/// - bad user input (files, configs, arguments) throws hattr::InputError, which the
///   CLI maps to exit code 2; every other hattr::Error maps to exit code 1;
/// - our own invariants are checked with HATTR_DEMAND (always on) and HATTR_ASSERT
///   (debug builds only);
/// - the servo path never throws: it returns status values.

#include <cassert>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace hattr {

/// Base of every exception hattr throws. A runtime failure (CLI exit code 1).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad input from a user: a file, a configuration, a command-line argument, a packet.
/// The message says what, where, what was expected and what was found (CLI exit code 2).
class InputError : public Error {
 public:
  using Error::Error;
};

/// One of hattr's own invariants does not hold: a bug in hattr, not in the input.
class InvariantError : public Error {
 public:
  using Error::Error;
};

}  // namespace hattr

/// Throws hattr::InputError with a fmt-formatted message unless `cond` holds.
#define HATTR_THROW_UNLESS(cond, ...)                                   \
  do {                                                                   \
    if (!(cond)) throw ::hattr::InputError(::fmt::format(__VA_ARGS__)); \
  } while (false)

/// Always-on check of an internal invariant; throws hattr::InvariantError.
#define HATTR_DEMAND(cond, ...)                                                  \
  do {                                                                           \
    if (!(cond))                                                                 \
      throw ::hattr::InvariantError(::fmt::format("{}:{}: invariant '{}' failed: {}", \
                                                  __FILE__, __LINE__, #cond,     \
                                                  ::fmt::format(__VA_ARGS__)));  \
  } while (false)

/// Debug-only check of an internal invariant (compiled out with NDEBUG).
#define HATTR_ASSERT(cond) assert(cond)
