// The sim module's exception: a tool that failed, a SUMO that would not start or dropped its
// connection, or a scenario that cannot be built. Messages name the file or command to look at.
#pragma once

#include <stdexcept>

namespace corridor::sim {

class SimError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace corridor::sim
