#include "peelcd/core/exact/reference.h"

#include "peelcd/core/pairs.h"
#include "peelcd/core/exact/narrow_phase.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <limits>

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

std::vector<std::uint64_t> exact_self_pairs(const Mesh& mesh, SelfAdjacency adjacency) {
  std::vector<std::uint32_t> rep;
  vertex_representatives(mesh, adjacency, rep);
  std::vector<Box> boxes = triangle_boxes(mesh);
  std::vector<std::uint64_t> out;
  CGAL::box_self_intersection_d(
      boxes.begin(), boxes.end(),
      [&](const Box& x, const Box& y) {
        const std::uint32_t t = std::min(x.info(), y.info()), u = std::max(x.info(), y.info());
        if (triangles_adjacent(mesh, rep, t, u)) return;
        if (triangles_intersect(corners(mesh, t), corners(mesh, u))) out.push_back(pack_pair(t, u));
      },
      std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::uint64_t> exact_pair_reference(const std::vector<Object>& objects, std::size_t ia, std::size_t ib,
                                                SelfAdjacency adjacency) {
  if (ia == ib) return exact_self_pairs(objects[ia].mesh, adjacency);
  return exact_colliding_pairs(objects[ia].mesh, objects[ib].mesh);
}

// A triangle's closed box for the sweep below (a named namespace: BoxScratch::Impl, a class with
// external linkage, holds vectors of it).
namespace reference_sweep {
struct SweepBox {
  double lo[3], hi[3];
  std::uint32_t tri;
};
}  // namespace reference_sweep
using reference_sweep::SweepBox;

namespace {

SweepBox sweep_box(const Mesh& m, std::uint32_t t) {
  SweepBox b;
  const Tri& f = m.triangles[t];
  for (int k = 0; k < 3; ++k) {
    const double x = m.vertices[f[0]][k], y = m.vertices[f[1]][k], z = m.vertices[f[2]][k];
    b.lo[k] = std::min({x, y, z});
    b.hi[k] = std::max({x, y, z});
  }
  b.tri = t;
  return b;
}

// The boxes overlap (closed) on the two axes other than `axis`.
bool overlap_other(const SweepBox& x, const SweepBox& y, int axis) {
  for (int k = 0; k < 3; ++k)
    if (k != axis && (x.hi[k] < y.lo[k] || y.hi[k] < x.lo[k])) return false;
  return true;
}
}  // namespace

void cgal_box_overlap_pairs(const Mesh& a, const std::vector<std::uint32_t>& ta, const Mesh& b,
                            const std::vector<std::uint32_t>& tb, std::vector<std::uint64_t>& out) {
  std::vector<Box> ba, bb;
  ba.reserve(ta.size());
  bb.reserve(tb.size());
  for (const std::uint32_t t : ta) ba.push_back(triangle_box(a, t));
  for (const std::uint32_t t : tb) bb.push_back(triangle_box(b, t));
  // Closed boxes: touching boxes are reported (CGAL's default, named).
  CGAL::box_intersection_d(ba.begin(), ba.end(), bb.begin(), bb.end(),
                           [&](const Box& x, const Box& y) { out.push_back(pack_pair(x.info(), y.info())); },
                           std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
}

struct BoxScratch::Impl {
  std::vector<SweepBox> a, b;
};
BoxScratch::BoxScratch() : impl(std::make_unique<Impl>()) {}
BoxScratch::~BoxScratch() = default;

// Sweep and prune over the two lists sorted by their boxes' lower x: each box
// meets the boxes of the other list that start at or after it and before its end; a pair is found
// from the box that starts first (ties: from A's side), so once. Closed boxes: touching boxes are
// reported. (The exact reference above keeps CGAL's
// box_intersection_d: the two are checked against each other by every --check.)
void box_overlap_pairs(const Mesh& a, const std::vector<std::uint32_t>& ta, const Mesh& b,
                       const std::vector<std::uint32_t>& tb, std::vector<std::uint64_t>& out, BoxScratch* scratch,
                       double margin) {
  std::vector<SweepBox> own_a, own_b;
  std::vector<SweepBox>& ba = scratch ? scratch->impl->a : own_a;
  std::vector<SweepBox>& bb = scratch ? scratch->impl->b : own_b;
  ba.clear();
  bb.clear();
  for (const std::uint32_t t : ta) {
    ba.push_back(sweep_box(a, t));
    for (int k = 0; k < 3; ++k) ba.back().lo[k] -= margin, ba.back().hi[k] += margin;
  }
  for (const std::uint32_t t : tb) bb.push_back(sweep_box(b, t));
  if (ba.empty() || bb.empty()) return;
  const int ax = 0;  // along x (choosing the axis by the boxes' spread cost more than it saved here)
  const auto by_lo = [](const SweepBox& x, const SweepBox& y) { return x.lo[ax] < y.lo[ax]; };
  std::sort(ba.begin(), ba.end(), by_lo);
  std::sort(bb.begin(), bb.end(), by_lo);
  std::size_t i = 0, j = 0;
  while (i < ba.size() && j < bb.size()) {
    if (ba[i].lo[ax] <= bb[j].lo[ax]) {
      const SweepBox& x = ba[i++];
      for (std::size_t k = j; k < bb.size() && !(bb[k].lo[ax] > x.hi[ax]); ++k)
        if (overlap_other(x, bb[k], ax)) out.push_back(pack_pair(x.tri, bb[k].tri));
    } else {
      const SweepBox& y = bb[j++];
      for (std::size_t k = i; k < ba.size() && !(ba[k].lo[ax] > y.hi[ax]); ++k)
        if (overlap_other(ba[k], y, ax)) out.push_back(pack_pair(ba[k].tri, y.tri));
    }
  }
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
