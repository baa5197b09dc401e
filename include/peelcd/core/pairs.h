#pragma once
// Pairs of triangles, the one unit every path shares: a triangle's corners, a contact (two
// triangles that meet, their segment and kind), an ID pair read back from the image stage, a
// couple packed in 64 bits, and the two sorts every path's lists go through (candidate keys
// sorted and made unique; contacts by their triangles), both on the one radix sort of 64-bit keys.
#include "peelcd/core/mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace peelcd {

using TriangleCorners = std::array<Vec3, 3>;

// How two intersecting triangles meet, decided with exact predicates
// (the narrow phase, peelcd/core/exact/narrow_phase.h):
//   crossing:   each triangle has corners strictly on both sides of the other's plane (they
//               penetrate);
//   touching:   not coplanar, and one triangle lies on one closed side of the other's plane
//               (contact without penetration: a vertex, an edge or a face resting on the other);
//   coplanar:   all six corners in one plane, overlapping;
//   degenerate: one of the triangles has no area (collinear or repeated corners);
//   unclassified: they meet (exact), neither kind nor segment asked for (ContactDetail::pairs).
enum class ContactKind { crossing, touching, coplanar, degenerate, unclassified };
const char* to_string(ContactKind kind);

struct Contact {
  std::uint32_t tri_a = 0, tri_b = 0;  // triangle indices in A's and B's file order
  Vec3 p = Vec3::Zero(), q = Vec3::Zero();  // intersection segment (p == q for a point); both 0
                                            // when unclassified
  ContactKind kind = ContactKind::crossing;
  bool classified() const { return kind != ContactKind::unclassified; }
};

inline TriangleCorners corners(const Mesh& m, std::uint32_t t) {
  return {m.vertices[m.triangles[t][0]], m.vertices[m.triangles[t][1]], m.vertices[m.triangles[t][2]]};
}

// A PCS as read back: one ID of object A and one of object B.
struct IdPair {
  std::uint32_t a, b;
};
inline bool operator==(const IdPair& x, const IdPair& y) { return x.a == y.a && x.b == y.b; }
inline bool operator<(const IdPair& x, const IdPair& y) { return x.a < y.a || (x.a == y.a && x.b < y.b); }

inline std::uint64_t pack_pair(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(a) << 32) | b;
}
inline std::uint32_t pair_a(std::uint64_t p) { return std::uint32_t(p >> 32); }
inline std::uint32_t pair_b(std::uint64_t p) { return std::uint32_t(p & 0xffffffffu); }

// Sorts `keys` (pack_pair values) ascending and drops repeats: a least-significant-digit radix
// sort over only the bits the keys use (8-bit digits below 2,048 keys, 11-bit ones from there),
// std::sort below kRadixContacts keys. `scratch` is reused storage.
void sort_unique_pairs(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& scratch);

// Contacts by (tri_a, tri_b): a pair's contacts in the order every path gives them. A 64-bit key
// per contact is sorted (by comparison below kRadixContacts, else by its indices' bits: 8-bit
// digits below 2,048 contacts, 11-bit ones from there, a digit all keys share skipped) and each
// contact moved once. At 228 contacts (the default scene) the keys' radix sort takes about a
// fifth of a comparison sort's time, at thousands of contacts the whole sort about a quarter.
constexpr std::size_t kRadixContacts = 32;
struct ContactSortScratch {  // kept by a caller that sorts every frame (no allocation once grown)
  std::vector<std::uint64_t> keys, spare;
  std::vector<Contact> sorted;
};
void sort_contacts(std::vector<Contact>& contacts, ContactSortScratch& scratch);
void sort_contacts(std::vector<Contact>& contacts);  // with scratch of its own

}  // namespace peelcd
