#include "peelcd/core/reference.h"

#include "peelcd/core/id_map.h"
#include "peelcd/core/narrow_phase.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>

namespace peelcd {
namespace {
using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;

Box triangle_box(const Mesh& m, std::uint32_t t) {
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = hi[k] = m.vertices[m.triangles[t][0]][k];
    for (int c = 1; c < 3; ++c) {
      lo[k] = std::min(lo[k], m.vertices[m.triangles[t][c]][k]);
      hi[k] = std::max(hi[k], m.vertices[m.triangles[t][c]][k]);
    }
  }
  return Box(lo, hi, t);
}

std::vector<Box> triangle_boxes(const Mesh& m) {
  std::vector<Box> boxes;
  boxes.reserve(m.triangles.size());
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t) boxes.push_back(triangle_box(m, t));
  return boxes;
}
}  // namespace

std::vector<std::uint64_t> exact_colliding_pairs(const Mesh& a, const Mesh& b) {
  std::vector<Box> ba = triangle_boxes(a), bb = triangle_boxes(b);
  std::vector<std::uint64_t> out;
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(),
                           [&](const Box& x, const Box& y) {
                             if (triangles_intersect(corners(a, x.info()), corners(b, y.info())))
                               out.push_back(pack_pair(x.info(), y.info()));
                           });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

struct BoxScratch::Impl {
  std::vector<Box> a, b;
};
BoxScratch::BoxScratch() : impl(std::make_unique<Impl>()) {}
BoxScratch::~BoxScratch() = default;

void box_overlap_pairs(const Mesh& a, const std::vector<std::uint32_t>& ta, const Mesh& b,
                       const std::vector<std::uint32_t>& tb, std::vector<std::uint64_t>& out, BoxScratch* scratch) {
  std::vector<Box> own_a, own_b;
  std::vector<Box>& ba = scratch ? scratch->impl->a : own_a;
  std::vector<Box>& bb = scratch ? scratch->impl->b : own_b;
  ba.clear();
  bb.clear();
  ba.reserve(ta.size());
  bb.reserve(tb.size());
  for (const std::uint32_t t : ta) ba.push_back(triangle_box(a, t));
  for (const std::uint32_t t : tb) bb.push_back(triangle_box(b, t));
  // Closed boxes: touching boxes are reported (CGAL's default, named).
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(),
                           [&](const Box& x, const Box& y) { out.push_back(pack_pair(x.info(), y.info())); },
                           std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
}

Score score_contacts(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported) {
  Score s;
  s.exact = exact.size();
  for (const Contact& c : reported)
    (std::binary_search(exact.begin(), exact.end(), pack_pair(c.tri_a, c.tri_b)) ? s.found : s.false_contacts)++;
  s.missed = s.exact - s.found;
  return s;
}

}  // namespace peelcd
