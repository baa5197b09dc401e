#pragma once
#include <stdexcept>

namespace peelcd {

// Bad user input (a file, a scene, an option). The message names the input and the problem;
// the command line turns it into exit status 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace peelcd
