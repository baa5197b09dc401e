#include "peelcd/core/image/cpu_peel.h"
#include "peelcd/core/primitives.h"

#include <catch2/catch.hpp>

#include <algorithm>

using namespace peelcd;

// Box B pokes through the x = 1 face of box A. The ROI is [0.5, 1] x [0.25, 0.75]^2 and its six
// faces are exactly A's x = 1 face and five faces of B, so every ray through the ROI meets two
// surfaces: two layers, and PCS only near the rim where A's face meets B's sides.
//
//    z ^     +-----------+            A = [0, 1]^3
//      |     |        +--|-----+      B = [0.5, 1.5] x [0.25, 0.75]^2
//      |     |   A    |  | B   |
//      |     |        +--|-----+
//      |     +-----------+
//      +------------------> x
TEST_CASE("CPU model: two crossing boxes peel into two layers with PCS on the rim", "[cpu_peel]") {
  const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = make_box(Vec3(0.5, 0.25, 0.25), Vec3(1.5, 0.75, 0.75));
  const Aabb roi = intersection(bounds(a), bounds(b));
  const RoiView view = make_roi_view(roi, view_frame(30, 20), 128, 1e-6);
  // Along d(30, 20) rays enter the ROI through B and leave through A or B; alternate peeling
  // sees the pair only when B, the nearer object, is peeled first.
  for (const auto& [mode, a_first] : {std::pair{PeelMode::alternate, false}, std::pair{PeelMode::full, true}}) {
    const CpuPeelResult r = cpu_peel(a, b, view, IdMode::unique, view.texel(), a_first, mode, 1.0);
    CHECK(r.layers == 2);
    REQUIRE_FALSE(r.pcs.empty());
    for (const IdPair& p : r.pcs) {
      CHECK((p.a == 10 || p.a == 11));  // A's x = hi face (core/primitives.cpp)
      CHECK(p.b < 8);                   // B's y and z faces
    }
  }
}

TEST_CASE("CPU model: full peeling finds a superset of alternate peeling's PCS", "[cpu_peel]") {
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32);
  const Mesh b = make_uv_sphere(Vec3(0.9, 0.4, 0.2), 0.7, 12, 24);
  const RoiView view = make_roi_view(intersection(bounds(a), bounds(b)), view_frame(60, 10), 96, 1e-6);
  for (IdMode ids : {IdMode::unique, IdMode::paper}) {
    const auto alt = cpu_peel(a, b, view, ids, view.texel(), false, PeelMode::alternate, 0.0).pcs;
    const auto full = cpu_peel(a, b, view, ids, view.texel(), false, PeelMode::full, 0.0).pcs;
    REQUIRE_FALSE(alt.empty());
    CHECK(std::includes(full.begin(), full.end(), alt.begin(), alt.end()));
    CHECK(full.size() > alt.size());
  }
}
