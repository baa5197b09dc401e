// Fuzzes the scene parser: any input is either a scene or an InputError, never a crash.
#include "peelcd/io/error.h"
#include "peelcd/io/scene.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    peelcd::parse_scene(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", "/nonexistent");
  } catch (const peelcd::InputError&) {
  }
  return 0;
}
