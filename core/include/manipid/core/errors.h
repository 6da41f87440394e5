// errors.h — the exceptions the core throws, for both families (paper/ and robot/) and every layer above.
//
// Three kinds, and only these cross the core's interface:
//   InputError          the caller's input cannot be used (a size, a value, a missing column); field()
//                       names the input at fault ("m5", "q3", "half_length", "link[panda_link3]") so the
//                       command line and the service can point at it;
//   IdentificationError every input was well-formed on its own, yet no estimate can be formed (the cost
//                       is not a finite number at the start); the message says what to check;
//   Interrupted         the caller's cancel flag was set (a user's cancel, a shutdown, a time limit) and
//                       a long step stopped at one of its checkpoints, inside the step rather than after
//                       it: nothing is returned, and the caller knows why it asked.
// Everything else an algorithm finds (a direction the data do not excite, a fit that did not converge) is
// reported in its result, not thrown.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>
#include <utility>

namespace manipid {

/// Thrown for invalid user input (unknown parameter names, wrong sizes, bad values).
/// `field` names the offending input (e.g. "m5", "q3", "half_length") so callers can
/// report it precisely.
class InputError : public std::invalid_argument {
 public:
  InputError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

/// The identification could not produce an estimate although each input was well-formed on
/// its own: the cost is not a finite number at the starting values (or at the end). The
/// message says so in the user's terms and what to check.
class IdentificationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A long step (base parameters, an excitation's criterion, ...) stopped at a checkpoint because its
/// caller's cancel flag was set. what() names the step.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The checkpoint of a long step: throws Interrupted naming `step` when `cancel` is set (nullptr: never).
inline void checkpoint(const std::atomic<bool>* cancel, const char* step) {
  if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) throw Interrupted(std::string(step) + " was interrupted");
}

}  // namespace manipid
