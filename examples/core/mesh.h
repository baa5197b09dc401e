#pragma once
// The example project's own header of this name: it must not clash with peelcd's.
namespace app {
struct Mesh {
  int id = 0;
};
}  // namespace app
