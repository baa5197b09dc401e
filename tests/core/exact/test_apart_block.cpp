// The planes' test a block of couples at a time (core/exact/apart_block.h): lane by lane the
// answer of the scalar certified plane sides, never a couple that meets, and the narrow phase's
// contacts unchanged by it.
#include "exact/apart_block.h"
#include "exact/certified.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/aabb.h"
#include "peelcd/core/exact/self.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

using namespace peelcd;
using exact_detail::ApartBlock;

namespace {

// Couples of every kind the exact test meets: random and far, crossing, touching at a corner
// or an edge (integer coordinates: exactly on a plane), nearly coplanar within rounding,
// without area, at scales from 1e-6 to 1e6.
std::vector<std::pair<TriangleCorners, TriangleCorners>> couples(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-2, 2);
  const auto point = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
  const auto lattice = [&] { return Vec3(small(rng), small(rng), small(rng)); };
  std::vector<std::pair<TriangleCorners, TriangleCorners>> out;
  for (std::size_t i = 0; i < n; ++i) {
    TriangleCorners a{point(), point(), point()}, b{point(), point(), point()};
    switch (i % 6) {
      case 0:  // random, often crossing
        break;
      case 1:  // on a lattice: corners exactly on the other's plane, shared corners and edges
        a = {lattice(), lattice(), lattice()};
        b = {lattice(), lattice(), lattice()};
        break;
      case 2: {  // B within rounding of A's plane
        const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]);
        for (Vec3& p : b) p -= n * (n.dot(p - a[0]) / n.squaredNorm()) - n * (1e-17 * unit(rng));
        break;
      }
      case 3:  // sharing a corner
        b[0] = a[1];
        break;
      case 4:  // without area
        b[2] = b[0] + 2.0 * (b[1] - b[0]);
        break;
      case 5: {  // far apart, at a scale
        const double s = std::pow(10.0, double(int(i % 13) - 6));
        for (Vec3& p : a) p *= s;
        for (Vec3& p : b) p = p * s + Vec3(3.0 * s, 0, 0);
        break;
      }
    }
    out.emplace_back(a, b);
  }
  return out;
}

// Whether certain_plane_sides(plane, t) decides by its bound alone that t lies strictly on one
// side (its axis-plane shortcut, which the lanes leave to the scalar test, excluded).
bool bound_says_one_side(const TriangleCorners& plane, const TriangleCorners& t) {
  int s[3];
  return exact_detail::axis_plane(plane) < 0 && exact_detail::certain_plane_sides(plane, t, s) &&
         exact_detail::one_open_side(s);
}

}  // namespace

TEST_CASE("the block's planes' test answers as the scalar certified plane sides, lane by lane", "[narrow][apart]") {
  const auto all = couples(6000, 7);
  ApartBlock block;
  std::mt19937 rng(3);
  std::size_t at = 0, apart = 0, both_ways = 0;
  while (at < all.size()) {
    const std::size_t m = std::min<std::size_t>(all.size() - at, 1 + rng() % ApartBlock::kSize);  // partial blocks too
    for (std::size_t i = 0; i < m; ++i) block.put(std::uint32_t(at + i), 0, all[at + i].first, all[at + i].second);
    REQUIRE(block.size() == m);
    // The same answers from every instruction set (the default last: its sides are kept).
    const std::uint64_t sse2 = block.apart(ApartBlock::Lanes::sse2);
    const std::uint64_t portable = block.apart(ApartBlock::Lanes::portable);
    const std::uint64_t bits = block.apart();
    REQUIRE(sse2 == bits);
    REQUIRE(portable == bits);
    if (m < ApartBlock::kSize) REQUIRE((bits >> m) == 0);
    for (std::size_t i = 0; i < m; ++i) {
      const auto& [a, b] = all[at + i];
      INFO("couple " << at + i);
      const bool lane = (bits >> i) & 1;
      int sa[3], sb[3];
      const bool scalar = (exact_detail::certain_plane_sides(a, b, sb) && exact_detail::one_open_side(sb)) ||
                          (exact_detail::certain_plane_sides(b, a, sa) && exact_detail::one_open_side(sa));
      if (lane) CHECK(scalar);            // only what the scalar test certifies,
      if (lane) CHECK_FALSE(triangles_meet(a, b));  // so never a couple that meets;
      if (bound_says_one_side(a, b) || bound_says_one_side(b, a)) CHECK(lane);  // all that its bound does
      apart += lane;
      both_ways += lane && bound_says_one_side(b, a) && !bound_says_one_side(a, b);
    }
    block.clear();
    at += m;
  }
  // The families hold both answers, and couples that only B's plane separates.
  CHECK(apart > all.size() / 5);
  CHECK(apart < all.size());
  CHECK(both_ways > 0);
}

TEST_CASE("the sides a block hands on are the scalar test's own certified signs", "[narrow][apart]") {
  const auto all = couples(3000, 5);
  ApartBlock block;
  std::size_t known_b = 0, known_a = 0, drained = 0;
  const auto check = [&](std::uint32_t, std::uint32_t, const TriangleCorners& a, const TriangleCorners& b,
                         const KnownSides& sides) {
    ++drained;
    int s[3];
    if (sides.b_known) {
      ++known_b;
      REQUIRE(exact_detail::certain_plane_sides(a, b, s));
      CHECK((s[0] == sides.b[0] && s[1] == sides.b[1] && s[2] == sides.b[2]));
      CHECK(sides.b[0] * sides.b[1] * sides.b[2] != 0);
    }
    if (sides.a_known) {
      ++known_a;
      REQUIRE(exact_detail::certain_plane_sides(b, a, s));
      CHECK((s[0] == sides.a[0] && s[1] == sides.a[1] && s[2] == sides.a[2]));
      CHECK(sides.a[0] * sides.a[1] * sides.a[2] != 0);
    }
    // The answer with the signs handed on is the answer without them.
    Contact with, without;
    ContactTest t1, t2;
    CHECK(t1(a, b, with, sides) == t2(a, b, without));
    CHECK((with.kind == without.kind && with.p == without.p && with.q == without.q));
    return true;
  };
  for (std::size_t i = 0; i < all.size(); ++i) {
    block.put(std::uint32_t(i), 0, all[i].first, all[i].second);
    if (block.full()) block.drain(check);
  }
  block.drain(check);
  CHECK(drained > 100);
  CHECK(known_b > drained / 4);  // the lattice and near-plane families leave some unknown
  CHECK(known_b < drained);
  CHECK(known_a > 0);
}

TEST_CASE("drain() hands on the couples not apart, in the order put, and stops when asked", "[narrow][apart]") {
  const auto all = couples(150, 11);
  ApartBlock block;
  for (std::size_t i = 0; i < 40; ++i) block.put(std::uint32_t(i), std::uint32_t(1000 + i), all[i].first, all[i].second);
  const std::uint64_t bits = block.apart();
  std::vector<std::uint32_t> seen;
  CHECK(block.drain([&](std::uint32_t ta, std::uint32_t tb, const TriangleCorners& a, const TriangleCorners& b,
                         const KnownSides&) {
    CHECK(tb == ta + 1000);
    CHECK(a == all[ta].first);
    CHECK(b == all[ta].second);
    seen.push_back(ta);
    return true;
  }));
  CHECK(block.size() == 0);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 0; i < 40; ++i)
    if (!((bits >> i) & 1)) expected.push_back(i);
  CHECK(seen == expected);
  REQUIRE(expected.size() >= 2);
  for (std::size_t i = 0; i < 40; ++i) block.put(std::uint32_t(i), 0, all[i].first, all[i].second);
  std::size_t calls = 0;
  CHECK_FALSE(block.drain([&](std::uint32_t, std::uint32_t, const TriangleCorners&, const TriangleCorners&,
                              const KnownSides&) { return ++calls < 2; }));
  CHECK(calls == 2);
  CHECK(block.size() == 0);
}

TEST_CASE("the narrow phases give each couple's own contact, in candidate order, across blocks", "[narrow][apart]") {
  // Two meshes of the couples' triangles: candidate i is (i, i), 6,000 of them (94 blocks).
  const auto all = couples(6000, 19);
  Mesh ma, mb;
  for (const auto& [a, b] : all) {
    const auto v = std::uint32_t(ma.vertices.size());
    for (int k = 0; k < 3; ++k) ma.vertices.push_back(a[k]), mb.vertices.push_back(b[k]);
    ma.triangles.push_back({v, v + 1, v + 2});
    mb.triangles.push_back({v, v + 1, v + 2});
  }
  std::vector<std::uint64_t> candidates;
  for (std::uint32_t i = 0; i < all.size(); ++i) candidates.push_back(pack_pair(i, i));
  std::vector<Contact> expected;
  for (std::uint32_t i = 0; i < all.size(); ++i) {
    Contact c;
    c.tri_a = c.tri_b = i;
    if (test_triangle_pair(all[i].first, all[i].second, c)) expected.push_back(c);
  }
  REQUIRE(expected.size() > 100);
  const auto same = [](const std::vector<Contact>& x, const std::vector<Contact>& y) {
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].tri_a != y[i].tri_a || x[i].tri_b != y[i].tri_b || x[i].kind != y[i].kind || x[i].p != y[i].p ||
          x[i].q != y[i].q)
        return false;
    return true;
  };
  for (const bool overlap : {false, true}) {
    std::vector<Contact> got;
    narrow_phase(ma, mb, candidates, got, overlap);
    std::vector<Contact> boxed;  // without the promise, couples with disjoint boxes are skipped first
    for (const Contact& c : expected)
      if (overlap || triangle_bounds(ma, c.tri_a).overlaps(triangle_bounds(mb, c.tri_b))) boxed.push_back(c);
    CHECK(same(got, boxed));
  }
  // A limit that falls inside a block: the first contacts in candidate order.
  for (const std::size_t limit : {std::size_t(1), std::size_t(37), expected.size() - 1}) {
    std::vector<Contact> got;
    narrow_phase(ma, mb, candidates, got, true, limit);
    CHECK(same(got, std::vector<Contact>(expected.begin(), expected.begin() + std::ptrdiff_t(limit))));
  }
  // The self narrow phase over one mesh holding both triangles of each couple.
  Mesh both = ma;
  const auto shift = std::uint32_t(ma.vertices.size());
  for (const Vec3& v : mb.vertices) both.vertices.push_back(v);
  for (const Tri& t : mb.triangles) both.triangles.push_back({t[0] + shift, t[1] + shift, t[2] + shift});
  std::vector<std::uint64_t> self_candidates;
  for (std::uint32_t i = 0; i < all.size(); ++i) self_candidates.push_back(pack_pair(i, i + std::uint32_t(all.size())));
  std::vector<Contact> got;
  self_narrow_phase(both, self_candidates, got);
  std::vector<Contact> shifted = expected;
  for (Contact& c : shifted) c.tri_b += std::uint32_t(all.size());
  CHECK(same(got, shifted));
}
