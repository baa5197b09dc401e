#include "peelcd/core/image/id_map.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <tuple>

using namespace peelcd;

// A fan around vertex 0 (the paper's Fig. 7): four triangles, three of which end in vertex 0.
//
//        2 ---- 1
//        | \  / |        triangles: {1,2,0} {2,3,0} {3,4,0} {0,4,1}
//        |  0   |        last vertex: 0, 0, 0, 1
//        | /  \ |
//        3 ---- 4
static Mesh fan() {
  Mesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0), Vec3(-1, -1, 0), Vec3(1, -1, 0)};
  m.triangles = {{1, 2, 0}, {2, 3, 0}, {3, 4, 0}, {0, 4, 1}};
  return m;
}

TEST_CASE("paper IDs stand for T(v), the triangles whose last vertex is v", "[ids]") {
  const Mesh m = fan();
  const IdMap map(m, IdMode::paper);
  CHECK(map.id_count() == 5);
  CHECK(map.triangles(0) == std::vector<std::uint32_t>{0, 1, 2});
  CHECK(map.triangles(1) == std::vector<std::uint32_t>{3});
  CHECK(map.triangles(2).empty());
  CHECK(corner_id(m, 3, 2, IdMode::paper) == 1);  // the provoking (last) corner
}

TEST_CASE("unique IDs stand for one triangle each", "[ids]") {
  const Mesh m = fan();
  const IdMap map(m, IdMode::unique);
  CHECK(map.id_count() == 4);
  for (std::uint32_t t = 0; t < 4; ++t) {
    CHECK(map.triangles(t) == std::vector<std::uint32_t>{t});
    for (int c = 0; c < 3; ++c) CHECK(corner_id(m, t, c, IdMode::unique) == t);
  }
}

TEST_CASE("PCS expand to de-duplicated candidate pairs T(a) x T(b)", "[ids]") {
  const Mesh m = fan();
  const IdMap pa(m, IdMode::paper), ub(m, IdMode::unique);
  std::vector<std::uint64_t> out;
  expand_pcs({{0, 3}, {0, 3}, {1, 0}}, pa, ub, out);
  const std::vector<std::uint64_t> expected = {pack_pair(0, 3), pack_pair(1, 3), pack_pair(2, 3), pack_pair(3, 0)};
  CHECK(out == expected);
  std::vector<std::uint64_t> bad;
  CHECK_THROWS_AS(expand_pcs({{9, 0}}, pa, ub, bad), std::out_of_range);
}

TEST_CASE("candidate pairs sort and de-duplicate like std::sort + std::unique, at every key width", "[ids]") {
  std::mt19937_64 rng(7);
  std::vector<std::uint64_t> scratch;
  // (triangles of A, of B, keys): short lists (std::sort), the radix sort's 8-bit digits (below
  // 2,048 keys) and 11-bit ones, 1 to 32 bits per side, many repeats.
  for (const auto& [na, nb, n] : std::vector<std::tuple<std::uint64_t, std::uint64_t, std::size_t>>{
           {1, 1, 5000}, {3, 1000, 20}, {3, 1000, 100}, {574, 1858, 300}, {1u << 20, 1u << 20, 1500}, {574, 1858, 20000}, {1, 1u << 20, 3000}, {1u << 31, 7, 4000},
           {std::uint64_t(1) << 32, std::uint64_t(1) << 32, 5000}, {50, 60, 100000}}) {
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < n; ++i) keys.push_back(pack_pair(std::uint32_t(rng() % na), std::uint32_t(rng() % nb)));
    for (std::size_t i = 0; i < n / 4; ++i) keys.push_back(keys[rng() % n]);  // repeats
    std::vector<std::uint64_t> expected = keys;
    std::sort(expected.begin(), expected.end());
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
    sort_unique_pairs(keys, scratch);
    INFO(na << " x " << nb << ", " << n << " keys");
    CHECK(keys == expected);
  }
  std::vector<std::uint64_t> none;
  sort_unique_pairs(none, scratch);
  CHECK(none.empty());
}

TEST_CASE("ID modes parse from their names only", "[ids]") {
  CHECK(parse_id_mode("paper") == IdMode::paper);
  CHECK(parse_id_mode("unique") == IdMode::unique);
  CHECK_FALSE(parse_id_mode("Paper").has_value());
  CHECK_FALSE(parse_id_mode("").has_value());
}

TEST_CASE("ring IDs stand for the whole one-ring of the last vertex", "[ids]") {
  const Mesh m = fan();
  const IdMap map(m, IdMode::ring);
  CHECK(map.triangles(0) == std::vector<std::uint32_t>{0, 1, 2, 3});  // every triangle touches 0
  CHECK(map.triangles(1) == std::vector<std::uint32_t>{0, 3});
  CHECK(map.triangles(4) == std::vector<std::uint32_t>{2, 3});
  CHECK(corner_id(m, 3, 2, IdMode::ring) == 1);  // same fragment ID as the paper's
  Mesh degenerate = m;
  degenerate.triangles.push_back({2, 2, 0});  // repeated corner: listed once
  CHECK(IdMap(degenerate, IdMode::ring).triangles(2) == std::vector<std::uint32_t>{0, 1, 4});
}

TEST_CASE("a rebuild keeps the map while the triangles and the mode stay, and follows any change", "[ids]") {
  Mesh m = fan();
  IdMap map(m, IdMode::ring);
  for (Vec3& p : m.vertices) p *= 2.0;  // a deforming mesh: same connectivity, same map
  map.rebuild(m, IdMode::ring);
  CHECK(map.triangles(1) == std::vector<std::uint32_t>{0, 3});
  map.rebuild(m, IdMode::paper);  // the mode changes the map
  CHECK(map.triangles(1) == std::vector<std::uint32_t>{3});
  m.triangles[3] = {0, 4, 2};  // a triangle changes in place, same count (a fracture)
  map.rebuild(m, IdMode::paper);
  CHECK(map.triangles(1).empty());
  CHECK(map.triangles(2) == std::vector<std::uint32_t>{3});
  m.vertices.push_back(Vec3(5, 5, 5));  // one more vertex: one more ID
  map.rebuild(m, IdMode::paper);
  CHECK(map.id_count() == 6);
  m.triangles.push_back({1, 5, 5});
  map.rebuild(m, IdMode::ring);
  CHECK(map.triangles(5) == std::vector<std::uint32_t>{4});
  CHECK(map.triangles(1) == std::vector<std::uint32_t>{0, 4});
}
