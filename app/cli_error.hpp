// The error a subcommand throws for bad command-line input; main prints it and exits with 2.
#pragma once

#include <stdexcept>

namespace corridor::app {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace corridor::app
