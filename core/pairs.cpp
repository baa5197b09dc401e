#include "peelcd/core/pairs.h"

#include "radix_sort.h"

#include <algorithm>

namespace peelcd {

static_assert(kRadixContacts == detail::kRadixFrom, "one threshold for the radix sorts");

const char* to_string(ContactKind kind) {
  switch (kind) {
    case ContactKind::crossing: return "crossing";
    case ContactKind::touching: return "touching";
    case ContactKind::coplanar: return "coplanar";
    case ContactKind::degenerate: return "degenerate";
    case ContactKind::unclassified: return "unclassified";
  }
  return "?";
}

void sort_unique_pairs(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& scratch) {
  if (keys.size() < kRadixContacts) {  // a radix pass costs a histogram: not worth it
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return;
  }
  std::uint32_t max_a = 0, max_b = 0;
  for (const std::uint64_t k : keys) max_a = std::max(max_a, pair_a(k)), max_b = std::max(max_b, pair_b(k));
  // Compact keys: a << bits_b | b keeps the order of (a, b) in bits_a + bits_b bits.
  const int bits_b = detail::bit_width(max_b), bits = detail::bit_width(max_a) + bits_b;
  for (std::uint64_t& k : keys) k = (std::uint64_t(pair_a(k)) << bits_b) | pair_b(k);
  detail::radix_sort_bits(keys, scratch, 0, bits);
  // Back to pack_pair keys, dropping repeats (now adjacent).
  const std::uint64_t mask_b = bits_b == 0 ? 0 : (~std::uint64_t(0) >> (64 - bits_b));
  std::size_t n = 0;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (i == 0 || keys[i] != keys[i - 1]) keys[n++] = keys[i];
  keys.resize(n);
  for (std::uint64_t& k : keys) k = pack_pair(std::uint32_t(k >> bits_b), std::uint32_t(k & mask_b));
}

void sort_contacts(std::vector<Contact>& contacts, ContactSortScratch& scratch) {
  const std::size_t n = contacts.size();
  const auto before = [](const Contact& x, const Contact& y) {
    return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
  };
  // In order already (one pass; a path that found them in order pays nothing more).
  if (std::is_sorted(contacts.begin(), contacts.end(), before)) return;
  std::uint32_t max_a = 0, max_b = 0;
  for (const Contact& c : contacts) max_a = std::max(max_a, c.tri_a), max_b = std::max(max_b, c.tri_b);
  // A key per contact: (tri_a, tri_b, its place) in one 64-bit word, when they fit.
  const int place_bits = detail::bit_width(n - 1), b_bits = detail::bit_width(max_b),
            key_bits = detail::bit_width(max_a) + b_bits;
  if (place_bits + key_bits > 64) {
    std::sort(contacts.begin(), contacts.end(), before);
    return;
  }
  std::vector<std::uint64_t>& keys = scratch.keys;
  std::vector<std::uint64_t>& spare = scratch.spare;
  keys.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    keys[i] = (((std::uint64_t(contacts[i].tri_a) << b_bits) | contacts[i].tri_b) << place_bits) | i;
  // The keys sorted (by comparison when few, else by their index bits), then each contact
  // moved once: a contact is 64 bytes, a key 8.
  if (n < kRadixContacts) {
    std::sort(keys.begin(), keys.end());
  } else {
    spare.resize(n);
    detail::radix_sort_bits(keys, spare, place_bits, place_bits + key_bits);
  }
  std::vector<Contact>& sorted = scratch.sorted;
  sorted.resize(n);
  const std::uint64_t place = (std::uint64_t(1) << place_bits) - 1;
  for (std::size_t i = 0; i < n; ++i) sorted[i] = contacts[keys[i] & place];
  contacts.swap(sorted);
}

void sort_contacts(std::vector<Contact>& contacts) {
  ContactSortScratch scratch;
  sort_contacts(contacts, scratch);
}

}  // namespace peelcd
