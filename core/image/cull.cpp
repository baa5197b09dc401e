#include "peelcd/core/image/cull.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace peelcd {
namespace {

using Entry = ContactCull::Entry;

// A grid of dims[0] x dims[1] x dims[2] cells over a box; a coordinate's cell is
// floor((x - lo) * inv) clamped to the grid: monotone in x (see cull.h).
struct Grid {
  Vec3 lo = Vec3::Zero();
  double inv[3] = {0, 0, 0};
  int dims[3] = {1, 1, 1};

  std::uint16_t cell(double x, int axis) const {
    const double f = (x - lo[axis]) * inv[axis];
    if (!(f > 0.0)) return 0;
    if (f >= double(dims[axis] - 1)) return std::uint16_t(dims[axis] - 1);
    return std::uint16_t(f);
  }
  std::size_t cells() const { return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]); }
};

Grid make_grid(const Aabb& box, std::size_t triangles) {
  Grid g;
  g.lo = box.lo;
  const Vec3 e = box.extent();
  const double longest = e.maxCoeff();
  // A point, or a box whose extent overflows (coordinates near 1e308): one cell.
  if (!(longest > 0.0) || !std::isfinite(longest)) return g;
  const double target = double(std::clamp<std::size_t>(triangles * kCullCellsPerTriangle, 1, kMaxCullCells));
  // Cubic cells of side s with about `target` of them; a flat axis gets one cell. In units of the
  // longest side (each in [0, 1], the volume in [1e-9, 1]): with coordinates near 1e-110 the
  // volume itself underflows to 0, and 0 / 0 cells is no count.
  double volume = 1.0;
  for (int i = 0; i < 3; ++i) volume *= std::max(e[i] / longest, 1e-3);
  const double s = std::cbrt(volume / target);
  for (int i = 0; i < 3; ++i) g.dims[i] = int(std::clamp(std::floor(e[i] / longest / s), 1.0, 1024.0));
  while (g.cells() > kMaxCullCells) *std::max_element(g.dims, g.dims + 3) /= 2;
  for (int i = 0; i < 3; ++i) g.inv[i] = e[i] > 0.0 ? double(g.dims[i]) / e[i] : 0.0;
  return g;
}

Entry entry_of(std::uint32_t tri, const Aabb& b, const Grid& g) {
  Entry e{tri, {}, {}};
  for (int i = 0; i < 3; ++i) {
    e.lo[i] = g.cell(b.lo[i], i);
    e.hi[i] = g.cell(b.hi[i], i);
  }
  return e;
}

// Bits [first, first + count) of `bits`: set them, or test whether any is set.
void set_bits(std::vector<std::uint64_t>& bits, std::size_t first, std::size_t count) {
  for (std::size_t i = first, end = first + count; i < end;) {
    const std::size_t word = i >> 6, bit = i & 63, n = std::min<std::size_t>(64 - bit, end - i);
    bits[word] |= (n == 64 ? ~std::uint64_t(0) : ((std::uint64_t(1) << n) - 1)) << bit;
    i += n;
  }
}
bool any_bit(const std::vector<std::uint64_t>& bits, std::size_t first, std::size_t count) {
  for (std::size_t i = first, end = first + count; i < end;) {
    const std::size_t word = i >> 6, bit = i & 63, n = std::min<std::size_t>(64 - bit, end - i);
    if (bits[word] & ((n == 64 ? ~std::uint64_t(0) : ((std::uint64_t(1) << n) - 1)) << bit)) return true;
    i += n;
  }
  return false;
}

// Rows of cells along the last axis are contiguous: a triangle's range is dims-0 x dims-1 runs.
template <class Row>
bool for_each_row(const Entry& e, const Grid& g, Row&& row) {
  for (int i = e.lo[0]; i <= e.hi[0]; ++i)
    for (int j = e.lo[1]; j <= e.hi[1]; ++j)
      if (row((std::size_t(i) * std::size_t(g.dims[1]) + std::size_t(j)) * std::size_t(g.dims[2]) + e.lo[2],
              std::size_t(e.hi[2] - e.lo[2] + 1)))
        return true;
  return false;
}

void mark(const std::vector<Entry>& entries, const Grid& g, std::vector<std::uint64_t>& bits) {
  bits.assign((g.cells() + 63) / 64, 0);
  for (const Entry& e : entries)
    for_each_row(e, g, [&](std::size_t first, std::size_t count) {
      set_bits(bits, first, count);
      return false;
    });
}

// Keeps the entries (and their boxes) for which keep(entry, box) holds, in order.
template <class Keep>
void compact(std::vector<Entry>& entries, std::vector<Aabb>& boxes, Keep&& keep) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (!keep(entries[i], boxes[i])) continue;
    entries[out] = entries[i];
    boxes[out] = boxes[i];
    ++out;
  }
  entries.resize(out);
  boxes.resize(out);
}

// Keeps the entries touching a cell of `other`; returns the box of the kept triangles.
Aabb keep_touching(std::vector<Entry>& entries, std::vector<Aabb>& boxes, const Grid& g,
                   const std::vector<std::uint64_t>& other) {
  Aabb kept_box;
  compact(entries, boxes, [&](const Entry& e, const Aabb& b) {
    const bool touches = for_each_row(e, g, [&](std::size_t first, std::size_t count) {
      return any_bit(other, first, count);
    });
    if (touches) {
      kept_box.extend(b.lo);
      kept_box.extend(b.hi);
    }
    return touches;
  });
  return kept_box;
}

// The triangles of `m` whose boxes touch `roi` (closed). Each vertex gets an outcode, one bit per
// side of the box it lies strictly beyond; a triangle whose three corners share a bit misses the
// box (the same test as its box's, exactly), and only the others get a box.
void gather(const Mesh& m, const Aabb& roi_in, double grow, std::vector<std::uint8_t>& outcodes,
            std::vector<Entry>& entries, std::vector<Aabb>& boxes) {
  const Aabb roi = roi_in.grown(grow);  // a box grown by `grow` touches the ROI: it touches the ROI grown by it
  entries.clear();
  boxes.clear();
  outcodes.resize(m.vertices.size());
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const Vec3& p = m.vertices[v];
    std::uint8_t code = 0;
    for (int i = 0; i < 3; ++i) code |= std::uint8_t((p[i] < roi.lo[i]) << (2 * i) | (p[i] > roi.hi[i]) << (2 * i + 1));
    outcodes[v] = code;
  }
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t) {
    const Tri& f = m.triangles[t];
    if (outcodes[f[0]] & outcodes[f[1]] & outcodes[f[2]]) continue;
    entries.push_back(Entry{t, {}, {}});
    boxes.push_back(triangle_bounds(m, t).grown(grow));
  }
}

}  // namespace

void cull_to_contact_region(const Mesh& a, const Mesh& b, const Aabb& roi, ContactCull& out, int max_rounds,
                            double margin) {
  const double grow = 0.5 * margin;
  max_rounds = std::clamp(max_rounds, 1, kMaxCullRounds);
  out.stats = CullStats{};
  out.kept_a.clear();
  out.kept_b.clear();
  out.box = Aabb{};
  out.median_edge = 0.0;
  if (roi.empty()) return;
  gather(a, roi, grow, out.outcodes, out.entries_a, out.boxes_a);
  out.entries_b.clear();  // none in the ROI when A has none (not the last call's)
  out.boxes_b.clear();
  if (!out.entries_a.empty()) gather(b, roi, grow, out.outcodes, out.entries_b, out.boxes_b);
  out.stats.in_roi_a = out.entries_a.size();
  out.stats.in_roi_b = out.entries_b.size();
  Aabb box = roi;
  while (!out.entries_a.empty() && !out.entries_b.empty() && out.stats.rounds < max_rounds) {
    const std::size_t before = out.entries_a.size() + out.entries_b.size();
    const Grid g = make_grid(box, before);
    for (std::size_t i = 0; i < out.entries_a.size(); ++i)
      out.entries_a[i] = entry_of(out.entries_a[i].tri, out.boxes_a[i], g);
    for (std::size_t i = 0; i < out.entries_b.size(); ++i)
      out.entries_b[i] = entry_of(out.entries_b[i].tri, out.boxes_b[i], g);
    // The smaller side marks its cells and filters the larger; the larger side's survivors
    // mark theirs and filter the smaller (a colliding pair's common cell survives both).
    const bool a_small = out.entries_a.size() <= out.entries_b.size();
    std::vector<Entry>& small = a_small ? out.entries_a : out.entries_b;
    std::vector<Entry>& large = a_small ? out.entries_b : out.entries_a;
    std::vector<Aabb>& small_boxes = a_small ? out.boxes_a : out.boxes_b;
    std::vector<Aabb>& large_boxes = a_small ? out.boxes_b : out.boxes_a;
    mark(small, g, out.cells_a);
    const Aabb box_large = keep_touching(large, large_boxes, g, out.cells_a);
    mark(large, g, out.cells_b);
    const Aabb box_small = keep_touching(small, small_boxes, g, out.cells_b);
    const Aabb& box_a = a_small ? box_small : box_large;
    const Aabb& box_b = a_small ? box_large : box_small;
    ++out.stats.rounds;
    box = intersection(box, intersection(box_a, box_b));
    if (box.empty()) {
      out.entries_a.clear();
      out.entries_b.clear();
      break;
    }
    const auto in_box = [&](const Entry&, const Aabb& b) { return b.overlaps(box); };
    compact(out.entries_a, out.boxes_a, in_box);
    compact(out.entries_b, out.boxes_b, in_box);
    if (out.entries_a.size() + out.entries_b.size() == before) break;  // nothing more to drop
  }
  if (out.entries_a.empty() || out.entries_b.empty()) return;  // no contact possible
  out.box = box;
  for (const Entry& e : out.entries_a) out.kept_a.push_back(e.tri);
  for (const Entry& e : out.entries_b) out.kept_b.push_back(e.tri);
  out.stats.kept_a = out.kept_a.size();
  out.stats.kept_b = out.kept_b.size();
  // The size of the contact's features, for edge_tile_resolution(): each kept triangle's mean
  // edge, the median over both objects (the finer mesh, having more triangles here, weighs more).
  out.edges.clear();
  for (const auto& [m, kept] : {std::pair{&a, &out.kept_a}, std::pair{&b, &out.kept_b}})
    for (const std::uint32_t t : *kept) {
      const Vec3 &p = m->vertices[m->triangles[t][0]], &q = m->vertices[m->triangles[t][1]],
                 &r = m->vertices[m->triangles[t][2]];
      out.edges.push_back(((p - q).norm() + (q - r).norm() + (r - p).norm()) / 3.0);
    }
  const auto mid = out.edges.begin() + std::ptrdiff_t(out.edges.size() / 2);
  std::nth_element(out.edges.begin(), mid, out.edges.end());
  out.median_edge = *mid;
}

}  // namespace peelcd
