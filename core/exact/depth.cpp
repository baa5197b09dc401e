// Penetration depth (peelcd/core/exact/depth.h): the depth along one direction from the couples'
// translation intervals, and the search over directions.
#include "peelcd/core/exact/depth.h"

#include "peelcd/core/aabb.h"
#include "peelcd/core/exact/relation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace peelcd {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// An orthonormal frame whose third axis is n.
struct Frame {
  Vec3 u, v, n;
  explicit Frame(const Vec3& dir) : n(dir) {
    const Vec3 a = std::abs(n.x()) <= std::abs(n.y()) && std::abs(n.x()) <= std::abs(n.z()) ? Vec3::UnitX()
                   : std::abs(n.y()) <= std::abs(n.z())                                     ? Vec3::UnitY()
                                                                                             : Vec3::UnitZ();
    u = n.cross(a).normalized();
    v = n.cross(u);
  }
  Vec3 local(const Vec3& p) const { return Vec3(u.dot(p), v.dot(p), n.dot(p)); }
};

double cross2(const Vec3& p, const Vec3& q) { return p.x() * q.y() - p.y() * q.x(); }

// The translations s along the local z axis for which triangle a (moved by s) meets triangle b:
// the vertical line through the origin across the hull of the nine differences b_i - a_j. Its
// lowest and highest points lie on a triangle of three of them whose shadow holds the origin (or
// on a segment or point where the shadow is degenerate).
bool meeting_interval(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, double& lo, double& hi) {
  Vec3 p[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p[3 * i + j] = b[i] - a[j];
  lo = kInf;
  hi = -kInf;
  const auto take = [&](double z) {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  };
  for (int k = 0; k < 9; ++k)
    if (p[k].x() == 0.0 && p[k].y() == 0.0) take(p[k].z());
  for (int k = 0; k < 9; ++k)
    for (int l = k + 1; l < 9; ++l) {
      if (cross2(p[k], p[l]) != 0.0) continue;  // the segment's line misses the origin
      const double dk = std::hypot(p[k].x(), p[k].y()), dl = std::hypot(p[l].x(), p[l].y());
      if (dk + dl == 0.0 || p[k].x() * p[l].x() + p[k].y() * p[l].y() > 0.0) continue;  // origin not between
      const double t = dk / (dk + dl);
      take(p[k].z() + t * (p[l].z() - p[k].z()));
    }
  for (int k = 0; k < 9; ++k)
    for (int l = k + 1; l < 9; ++l)
      for (int m = l + 1; m < 9; ++m) {
        const double area = cross2(p[l] - p[k], p[m] - p[k]);
        if (area == 0.0) continue;
        const double wk = cross2(p[l], p[m]), wl = cross2(p[m], p[k]), wm = cross2(p[k], p[l]);
        if (area > 0.0 ? (wk < 0.0 || wl < 0.0 || wm < 0.0) : (wk > 0.0 || wl > 0.0 || wm > 0.0)) continue;
        take((wk * p[k].z() + wl * p[l].z() + wm * p[m].z()) / area);
      }
  return lo <= hi;
}

// The same, faster, where both shadows have area: the meeting translations are the differences of
// the two planes' heights over the shadows' overlap (a convex polygon), extreme at its corners.
// Shadows too thin for their planes' heights to be well conditioned go to meeting_interval().
bool shadow_interval(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, double& lo, double& hi) {
  const double area_a = cross2(a[1] - a[0], a[2] - a[0]), area_b = cross2(b[1] - b[0], b[2] - b[0]);
  const auto size2 = [](const std::array<Vec3, 3>& t) {
    return std::max({(t[1] - t[0]).head<2>().squaredNorm(), (t[2] - t[1]).head<2>().squaredNorm(),
                     (t[0] - t[2]).head<2>().squaredNorm()});
  };
  if (!(std::abs(area_a) > 1e-6 * size2(a)) || !(std::abs(area_b) > 1e-6 * size2(b))) return meeting_interval(a, b, lo, hi);
  // Clip A's shadow (counter-clockwise) by B's three edges (counter-clockwise).
  double px[9], py[9], qx[9], qy[9];
  int n = 3;
  for (int k = 0; k < 3; ++k) {
    const int j = area_a > 0 ? k : 2 - k;
    px[k] = a[j].x(), py[k] = a[j].y();
  }
  for (int e = 0; e < 3 && n > 0; ++e) {
    const Vec3& u = b[area_b > 0 ? e : 2 - e];
    const Vec3& w = b[area_b > 0 ? (e + 1) % 3 : (4 - e) % 3];
    const double ex = w.x() - u.x(), ey = w.y() - u.y();
    const auto side = [&](double x, double y) { return ex * (y - u.y()) - ey * (x - u.x()); };
    int m = 0;
    for (int k = 0; k < n; ++k) {
      const int l = (k + 1) % n;
      const double sk = side(px[k], py[k]), sl = side(px[l], py[l]);
      if (sk >= 0) qx[m] = px[k], qy[m] = py[k], ++m;
      if ((sk > 0 && sl < 0) || (sk < 0 && sl > 0)) {
        const double t = sk / (sk - sl);
        qx[m] = px[k] + t * (px[l] - px[k]), qy[m] = py[k] + t * (py[l] - py[k]), ++m;
      }
    }
    n = m;
    std::copy(qx, qx + n, px);
    std::copy(qy, qy + n, py);
  }
  if (n == 0) return false;
  const auto plane = [](const std::array<Vec3, 3>& t, double area, double& gx, double& gy) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    gx = (e1.z() * e2.y() - e2.z() * e1.y()) / area;
    gy = (e2.z() * e1.x() - e1.z() * e2.x()) / area;
  };
  double gax, gay, gbx, gby;
  plane(a, area_a, gax, gay);
  plane(b, area_b, gbx, gby);
  lo = kInf;
  hi = -kInf;
  for (int k = 0; k < n; ++k) {
    const double za = a[0].z() + gax * (px[k] - a[0].x()) + gay * (py[k] - a[0].y());
    const double zb = b[0].z() + gbx * (px[k] - b[0].x()) + gby * (py[k] - b[0].y());
    lo = std::min(lo, zb - za);
    hi = std::max(hi, zb - za);
  }
  return true;
}

struct Interval {
  double lo, hi;
};

// The meshes seen along n: corners in the local frame, B's triangles in a grid over their shadows.
struct AlongN {
  std::vector<std::array<Vec3, 3>> ta, tb;
  std::vector<std::uint32_t> cell_first, cell_tris, stamp;
  std::vector<Interval> intervals;
};

void local_triangles(const Mesh& m, const Frame& f, std::vector<std::array<Vec3, 3>>& out) {
  out.resize(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) out[t][k] = f.local(m.vertices[m.triangles[t][k]]);
}

struct Shadow {
  double lo_x, lo_y, hi_x, hi_y;
};
Shadow shadow(const std::array<Vec3, 3>& t) {
  return {std::min({t[0].x(), t[1].x(), t[2].x()}), std::min({t[0].y(), t[1].y(), t[2].y()}),
          std::max({t[0].x(), t[1].x(), t[2].x()}), std::max({t[0].y(), t[1].y(), t[2].y()})};
}

// Every couple's interval into s.intervals, those ending after `after` only.
void couple_intervals(AlongN& s, double after) {
  s.intervals.clear();
  if (s.ta.empty() || s.tb.empty()) return;
  Shadow all{kInf, kInf, -kInf, -kInf};
  for (const auto& t : s.tb) {
    const Shadow h = shadow(t);
    all = {std::min(all.lo_x, h.lo_x), std::min(all.lo_y, h.lo_y), std::max(all.hi_x, h.hi_x), std::max(all.hi_y, h.hi_y)};
  }
  const int g = std::clamp(int(std::sqrt(double(s.tb.size()))), 1, 1024);
  const double wx = std::max(all.hi_x - all.lo_x, 1e-300) / g, wy = std::max(all.hi_y - all.lo_y, 1e-300) / g;
  const auto cx = [&](double x) { return std::clamp(int(std::floor((x - all.lo_x) / wx)), 0, g - 1); };
  const auto cy = [&](double y) { return std::clamp(int(std::floor((y - all.lo_y) / wy)), 0, g - 1); };
  // B's triangles per cell (CSR).
  s.cell_first.assign(std::size_t(g) * g + 1, 0);
  for (const auto& t : s.tb) {
    const Shadow h = shadow(t);
    for (int y = cy(h.lo_y); y <= cy(h.hi_y); ++y)
      for (int x = cx(h.lo_x); x <= cx(h.hi_x); ++x) ++s.cell_first[std::size_t(y) * g + x + 1];
  }
  for (std::size_t c = 0; c + 1 < s.cell_first.size(); ++c) s.cell_first[c + 1] += s.cell_first[c];
  s.cell_tris.resize(s.cell_first.back());
  std::vector<std::uint32_t> fill(s.cell_first.begin(), s.cell_first.end() - 1);
  for (std::uint32_t t = 0; t < s.tb.size(); ++t) {
    const Shadow h = shadow(s.tb[t]);
    for (int y = cy(h.lo_y); y <= cy(h.hi_y); ++y)
      for (int x = cx(h.lo_x); x <= cx(h.hi_x); ++x) s.cell_tris[fill[std::size_t(y) * g + x]++] = t;
  }
  s.stamp.assign(s.tb.size(), 0xffffffffu);
  for (std::uint32_t ia = 0; ia < s.ta.size(); ++ia) {
    const Shadow h = shadow(s.ta[ia]);
    if (h.hi_x < all.lo_x || h.lo_x > all.hi_x || h.hi_y < all.lo_y || h.lo_y > all.hi_y) continue;
    for (int y = cy(h.lo_y); y <= cy(h.hi_y); ++y)
      for (int x = cx(h.lo_x); x <= cx(h.hi_x); ++x) {
        const std::size_t c = std::size_t(y) * g + x;
        for (std::uint32_t k = s.cell_first[c]; k < s.cell_first[c + 1]; ++k) {
          const std::uint32_t ib = s.cell_tris[k];
          if (s.stamp[ib] == ia) continue;
          s.stamp[ib] = ia;
          const Shadow hb = shadow(s.tb[ib]);
          if (hb.hi_x < h.lo_x || hb.lo_x > h.hi_x || hb.hi_y < h.lo_y || hb.lo_y > h.hi_y) continue;
          double lo, hi;
          if (shadow_interval(s.ta[ia], s.tb[ib], lo, hi) && hi > after) s.intervals.push_back({lo, hi});
        }
      }
  }
}

// One vertex of each connected component of `m` (point_inside() says where each lies).
std::vector<Vec3> component_points(const Mesh& m) {
  std::vector<Vec3> out;
  for (const std::uint32_t v : analyse_shape(m).component_vertex) out.push_back(m.vertices[v]);
  return out;
}

// A translated by s n and B share interior without their surfaces crossing: a component of one
// inside the other (s inside a gap of the intervals: no vertex lies on the other surface).
bool contained(const Mesh& a, const Mesh& b, const std::vector<Vec3>& pa, const std::vector<Vec3>& pb, const Vec3& n,
               double s) {
  for (const Vec3& p : pa)
    if (point_inside(b, p + s * n)) return true;
  for (const Vec3& p : pb)
    if (point_inside(a, p - s * n)) return true;
  return false;
}

double depth_along(const Mesh& a, const Mesh& b, const Vec3& n, const std::vector<Vec3>& pa,
                   const std::vector<Vec3>& pb, AlongN& s, double* bound) {
  const Frame f(n);
  local_triangles(a, f, s.ta);
  local_triangles(b, f, s.tb);
  // Rounding of the events: a few ulps of the largest coordinate, the local frame's products.
  // Meetings that end within it of 0 are contacts at rest (touching), not crossings.
  double scale = 0.0;
  for (const Mesh* m : {&a, &b})
    for (const Vec3& p : m->vertices) scale = std::max(scale, p.cwiseAbs().maxCoeff());
  const double eps = 64.0 * std::numeric_limits<double>::epsilon() * std::max(scale, 1e-300);
  if (bound) *bound = eps;
  couple_intervals(s, eps);
  std::vector<Interval>& iv = s.intervals;
  std::sort(iv.begin(), iv.end(), [](const Interval& x, const Interval& y) { return x.lo < y.lo; });
  double at = 0.0;
  std::size_t i = 0;
  for (;;) {
    // Every interval starting at or before `at`: where they reach past it, the surfaces still
    // cross (an interval starting exactly at `at` is taken too: d errs toward separating).
    double reach = at;
    while (i < iv.size() && iv[i].lo <= at) reach = std::max(reach, iv[i++].hi);
    if (reach > at) {
      at = reach;
      continue;
    }
    if (i == iv.size()) break;  // past every meeting: apart
    const double next = iv[i].lo;
    if (!contained(a, b, pa, pb, n, 0.5 * (at + next))) break;  // a gap where neither holds the other
    at = next;
  }
  return at > 0.0 ? at + eps : 0.0;
}

// A canonical order of two meshes (swapping A and B computes the same pair): by size, then box,
// then coordinates.
bool canonical_first(const Mesh& a, const Mesh& b) {
  if (a.triangles.size() != b.triangles.size()) return a.triangles.size() < b.triangles.size();
  if (a.vertices.size() != b.vertices.size()) return a.vertices.size() < b.vertices.size();
  const Aabb ba = bounds(a), bb = bounds(b);
  for (int k = 0; k < 3; ++k)
    if (ba.lo[k] != bb.lo[k]) return ba.lo[k] < bb.lo[k];
  for (int k = 0; k < 3; ++k)
    if (ba.hi[k] != bb.hi[k]) return ba.hi[k] < bb.hi[k];
  for (std::size_t v = 0; v < a.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k)
      if (a.vertices[v][k] != b.vertices[v][k]) return a.vertices[v][k] < b.vertices[v][k];
  return true;
}

Vec3 area_normal(const Mesh& m, std::uint32_t t) {
  const TriangleCorners c = corners(m, t);
  return 0.5 * (c[1] - c[0]).cross(c[2] - c[0]);
}

// A direction in general position near `n`: turned by kDepthPerturbation about a fixed axis.
Vec3 general(const Vec3& n) {
  const Vec3 axis = Vec3(0.5772156649, 0.6180339887, 0.7071067812).normalized();
  Vec3 side = axis.cross(n);
  if (side.norm() < 1e-3) side = Vec3(0.8090169944, -0.3090169944, 0.5).cross(n);
  return (n + kDepthPerturbation * side.normalized()).normalized();
}

struct Candidate {
  Vec3 n;
  const char* source;
};

// The ordered search: A and B in canonical order.
PenetrationDepth search(const Mesh& a, const Mesh& b, const std::vector<Contact>& contacts, bool swapped) {
  PenetrationDepth r;
  const std::vector<Vec3> pa = component_points(a), pb = component_points(b);
  AlongN scratch;
  std::vector<Candidate> cands;
  // The contacts' area-weighted normals: B's outward normals push A out of B; A's inward ones too.
  // Summed in triangle order, whatever the contacts' order.
  Vec3 nb = Vec3::Zero(), na = Vec3::Zero();
  {
    std::vector<char> seen_a(a.triangles.size(), 0), seen_b(b.triangles.size(), 0);
    for (const Contact& c : contacts) {
      seen_a[swapped ? c.tri_b : c.tri_a] = 1;
      seen_b[swapped ? c.tri_a : c.tri_b] = 1;
    }
    for (std::uint32_t t = 0; t < a.triangles.size(); ++t)
      if (seen_a[t]) na -= area_normal(a, t);
    for (std::uint32_t t = 0; t < b.triangles.size(); ++t)
      if (seen_b[t]) nb += area_normal(b, t);
  }
  if (nb.norm() > 0.0) cands.push_back({nb.normalized(), "contact normals of B"});
  if (na.norm() > 0.0) cands.push_back({na.normalized(), "contact normals of A"});
  const Aabb box = intersection(bounds(a), bounds(b));
  if (!box.empty()) {
    const VolumeEstimate vol = overlap_volume(a, b, box, 64);
    if (vol.known && vol.gradient.norm() > 0.0) cands.push_back({(-vol.gradient).normalized(), "volume gradient"});
  }
  Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
  for (const Vec3& p : a.vertices) ca += p;
  for (const Vec3& p : b.vertices) cb += p;
  ca /= double(std::max<std::size_t>(1, a.vertices.size()));
  cb /= double(std::max<std::size_t>(1, b.vertices.size()));
  if ((ca - cb).norm() > 0.0) cands.push_back({(ca - cb).normalized(), "centroids"});
  for (int k = 0; k < 3; ++k) {
    cands.push_back({Vec3::Unit(k), "axis"});
    cands.push_back({-Vec3::Unit(k), "axis"});
  }
  // Every direction evaluated (d, its bound, n, the candidate it came from), sorted by d once the
  // global stage is done.
  struct Tried {
    double d, bound;
    Vec3 n;
    const char* source;
  };
  std::vector<Tried> tried;
  const auto evaluate = [&](const Vec3& n, const char* source) {
    double bnd = 0.0;
    const double d = depth_along(a, b, n, pa, pb, scratch, &bnd);
    ++r.directions;
    tried.push_back({d, bnd, n, source});
    return d;
  };
  bool touching = false;
  for (const Candidate& c : cands)
    if (evaluate(general(c.n), c.source) == 0.0) {
      touching = true;  // nothing shorter
      break;
    }
  // The global stage: kDepthGlobalDirections spread evenly over the sphere (a Fibonacci
  // lattice). The candidates alone can start the local search in another valley than the least
  // one's (tests/eval/test_depth.cpp: 1.18x the least a 300-direction search found on a torus
  // against a kitten).
  for (int i = 0; i < kDepthGlobalDirections && !touching; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / kDepthGlobalDirections, rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = i * 2.399963229728653;  // the golden angle
    touching = evaluate(general(Vec3(rho * std::cos(phi), rho * std::sin(phi), z)), "global") == 0.0;
  }
  std::stable_sort(tried.begin(), tried.end(), [](const Tried& x, const Tried& y) { return x.d < y.d; });
  Tried best = tried.front();
  // The local search from the kDepthStarts best directions at least a quarter radian apart: at
  // each, neighbours at angle theta around it, theta halved when none improves, at most
  // kDepthLocalEvaluations evaluations a start.
  std::vector<Vec3> starts;
  for (const Tried& t : tried) {
    if (touching || int(starts.size()) == kDepthStarts) break;
    bool apart = true;
    for (const Vec3& s : starts) apart = apart && s.dot(t.n) < std::cos(0.25);
    if (apart) starts.push_back(t.n);
  }
  for (std::size_t k = 0; k < starts.size() && best.d > 0.0; ++k) {
    Tried local = *std::find_if(tried.begin(), tried.end(), [&](const Tried& t) { return t.n == starts[k]; });
    double theta = 0.25;
    int used = 0;
    while (local.d > 0.0 && theta > 1e-3 && used < kDepthLocalEvaluations) {
      const Frame f(local.n);
      bool improved = false;
      for (int j = 0; j < 6 && used < kDepthLocalEvaluations && !improved; ++j) {
        const double phi = j * (M_PI / 3.0);
        const Vec3 n = (std::cos(theta) * local.n + std::sin(theta) * (std::cos(phi) * f.u + std::sin(phi) * f.v)).normalized();
        double bnd = 0.0;
        const double d = depth_along(a, b, n, pa, pb, scratch, &bnd);
        ++r.directions;
        ++used;
        if (d < local.d * (1.0 - 1e-9)) {
          local = {d, bnd, n, local.source};
          improved = true;
        }
      }
      if (!improved) theta *= 0.5;
    }
    if (local.d < best.d) best = local;
  }
  r.source = best.source;
  double best_d = best.d;
  const double best_bound = best.bound;
  // Surfaces that cross share interior, however little: an overlap under the rounding bound
  // (depth_along() then finds no meeting past it) is reported at the bound, not as 0, so that
  // d still errs toward separating and a crossing pair never has depth 0 (touching has).
  if (best_d == 0.0 && contact_relation(contacts) == Relation::crossing) best_d = best_bound;
  const Vec3 best_n = best.n;
  r.known = true;
  r.direction = best_n;
  r.depth = best_d;
  r.bound = best_bound;
  return r;
}

}  // namespace

double depth_along(const Mesh& a, const Mesh& b, const Vec3& n, double* bound) {
  AlongN scratch;
  return depth_along(a, b, n.normalized(), component_points(a), component_points(b), scratch, bound);
}

PenetrationDepth penetration_depth(const Mesh& a, const Mesh& b, const std::vector<Contact>& contacts) {
  for (const Mesh* m : {&a, &b}) {
    const std::string problem = analyse_shape(*m).problem();
    if (!problem.empty()) {
      PenetrationDepth r;
      r.reason = std::string(m == &a ? "A" : "B") + " is not a closed, outward mesh (" + problem + ")";
      return r;
    }
  }
  if (canonical_first(a, b)) return search(a, b, contacts, false);
  PenetrationDepth r = search(b, a, contacts, true);
  r.direction = -r.direction;
  // The candidates' names are from B's side seen as A: say them from the caller's side.
  if (r.source == "contact normals of B")
    r.source = "contact normals of A";
  else if (r.source == "contact normals of A")
    r.source = "contact normals of B";
  return r;
}

}  // namespace peelcd
