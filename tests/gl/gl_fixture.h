#pragma once
// One OSMesa context and pipeline per test process, reused by every test (as an application
// would reuse them across frames).
#include "core/cpu_peel.h"
#include "core/reference.h"
#include "gl/pipeline.h"
#include "gl_osmesa/osmesa_context.h"

#include <algorithm>
#include <set>

namespace peelcd::test {

inline gl::Pipeline& osmesa_pipeline() {
  static gl::OsmesaContext context;
  static gl::Pipeline pipeline(context);
  return pipeline;
}

// Exact pairs vs reported pairs of one object pair: every miss and every false contact counts.
struct Score {
  std::size_t exact = 0, found = 0, missed = 0, false_contacts = 0;
  double miss_ratio() const { return exact ? double(missed) / double(exact) : 0.0; }
};

inline Score score(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported) {
  Score s;
  s.exact = exact.size();
  for (const Contact& c : reported)
    (std::binary_search(exact.begin(), exact.end(), pack_pair(c.tri_a, c.tri_b)) ? s.found : s.false_contacts)++;
  s.missed = s.exact - s.found;
  return s;
}

}  // namespace peelcd::test
