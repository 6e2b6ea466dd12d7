// Typed errors of the localizer: bad sequences, calibration and options are reported, never guessed.
#pragma once

#include <stdexcept>
#include <string>

namespace corridor::localizer {

// A stereo sequence, calibration or pose file that cannot be used as given.
class SequenceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace corridor::localizer
